//! How the ocean is tessellated (paper section 2, Figure 1): one of the paper's two presets,
//! `auto` (from the camera's pixel footprint) or explicit sizes, the reading of the doubling
//! rule and the pattern. Plain data; `crate::lod` turns it into `LodParams` for a camera.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{ConfigError, invalid, positive};

/// How the ocean is tessellated: one of the paper's presets, `auto` (from the camera's pixel
/// footprint), or `custom` (the explicit fields of [`LodConfig`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LodChoice {
    /// The paper's high tessellation: 3 cm near the camera, double distance 18 m.
    PaperHigh,
    /// The paper's low tessellation: 90 cm near the camera, double distance 18 m.
    #[default]
    PaperLow,
    /// Triangles about one pixel wide at every distance.
    Auto,
    /// `near_size_m` and `double_distance_m` as given.
    Custom,
}

super::choice!(LodChoice { PaperHigh => "paper-high", PaperLow => "paper-low", Auto => "auto", Custom => "custom" });

/// The tessellation section of a scene: a choice plus overrides of its fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct LodConfig {
    pub preset: LodChoice,
    /// Overrides (required for `custom`).
    pub near_size_m: Option<f64>,
    pub double_distance_m: Option<f64>,
    pub generations: Option<u32>,
    pub max_distance_m: Option<f64>,
    pub reading: Option<Reading>,
}

/// Most doublings a tessellation may ask for.
pub const MAX_GENERATIONS: u32 = 40;

impl LodConfig {
    /// Checks each field on its own; whether the sizes fit together is checked by the
    /// tessellator once the preset's defaults are merged in.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (field, v) in [
            ("lod.near_size_m", self.near_size_m),
            ("lod.double_distance_m", self.double_distance_m),
            ("lod.max_distance_m", self.max_distance_m),
        ] {
            if let Some(v) = v {
                positive(field, v)?;
            }
        }
        if let Some(g) = self.generations
            && g > MAX_GENERATIONS
        {
            return Err(invalid(
                "lod.generations",
                &format!("at most {MAX_GENERATIONS}"),
                g,
            ));
        }
        if self.preset == LodChoice::Custom {
            for (field, v) in [
                ("lod.near_size_m", self.near_size_m),
                ("lod.double_distance_m", self.double_distance_m),
            ] {
                if v.is_none() {
                    return Err(invalid(
                        field,
                        "set when lod.preset = \"custom\"",
                        "nothing",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Which part of the nested grids is tessellated (the two patterns of the paper's Figure 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Pattern {
    /// Nested square grids in all directions, cut at the maximum distance.
    #[default]
    Square,
    /// Only the cells a perspective camera looking along `yaw_deg` (degrees from +x towards +z,
    /// the ocean's convention) with horizontal field of view `hfov_deg` can see, with
    /// the tessellator's angular margin on each side; cells closer than the camera height are kept too,
    /// as a camera pitched down sees them.
    Frustum { yaw_deg: f64, hfov_deg: f64 },
}

impl fmt::Display for Pattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Pattern::Square => write!(f, "square"),
            Pattern::Frustum { yaw_deg, hfov_deg } => write!(f, "frustum:{yaw_deg}:{hfov_deg}"),
        }
    }
}

/// Parses `square` or `frustum:YAW_DEG:HFOV_DEG` (for command lines).
impl FromStr for Pattern {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("pattern must be `square` or `frustum:YAW_DEG:HFOV_DEG` (got `{s}`)");
        let mut parts = s.split(':');
        match parts.next() {
            Some("square") if parts.next().is_none() => Ok(Pattern::Square),
            Some("frustum") => {
                let mut num = || parts.next().and_then(|p| p.trim().parse::<f64>().ok());
                let (yaw_deg, hfov_deg) = (num().ok_or_else(bad)?, num().ok_or_else(bad)?);
                if parts.next().is_some() {
                    return Err(bad());
                }
                Ok(Pattern::Frustum { yaw_deg, hfov_deg })
            }
            _ => Err(bad()),
        }
    }
}

/// Readings of the doubling rule (see `crate::lod` for the triangle counts of each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Reading {
    /// As `nested`, but the ring that reaches the maximum distance is kept whole (a full square,
    /// not cut at the horizon).
    #[default]
    NestedWhole,
    /// Ring k ends at d 2^k (d, 2d, 4d, ...); the generation cap ends the tessellation.
    Nested,
    /// Ring k is d 2^k wide, ending at d (2^(k+1) - 1) (d, 3d, 7d, ...: the paper's worked
    /// example); the generation cap ends the tessellation.
    Widths,
    /// As `nested`, but the cap only stops the doubling: the last generation reaches the
    /// maximum distance.
    NestedToHorizon,
    /// As `widths`, but the cap only stops the doubling.
    WidthsToHorizon,
}

super::choice!(Reading { NestedWhole => "nested-whole", Nested => "nested", Widths => "widths", NestedToHorizon => "nested-to-horizon", WidthsToHorizon => "widths-to-horizon" });
