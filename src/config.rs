//! The scene description: one TOML file (or the defaults) holding the ocean case, the LOD
//! tessellation, the camera, the sky, the water and the render settings, and its validation.
//! Unknown keys are errors, and every error names the offending field as it is spelled in the
//! file (e.g. `camera.height_m must be finite and > 0 (got -2)`).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::lod::{LodParams, Pattern, Preset, Reading};
use crate::ocean::OceanParams;
use crate::render::{AnalyticSky, NormalMode, Projection, TraceSettings, Water};

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {message}", path.display())]
    Parse { path: PathBuf, message: String },
    #[error("{field} must be {requirement} (got {got})")]
    Invalid {
        field: String,
        requirement: String,
        got: String,
    },
    #[error(transparent)]
    Ocean(#[from] crate::ocean::OceanError),
    #[error(transparent)]
    Lod(#[from] crate::lod::LodError),
}

fn invalid(field: &str, requirement: &str, got: impl std::fmt::Display) -> ConfigError {
    ConfigError::Invalid {
        field: field.into(),
        requirement: requirement.into(),
        got: got.to_string(),
    }
}

/// How the ocean is tessellated: one of the paper's presets, `auto` (from the camera's pixel
/// footprint), or `custom` (the explicit fields below).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LodChoice {
    PaperHigh,
    #[default]
    PaperLow,
    Auto,
    Custom,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

impl Default for LodConfig {
    fn default() -> Self {
        LodConfig {
            preset: LodChoice::PaperLow,
            near_size_m: None,
            double_distance_m: None,
            generations: None,
            max_distance_m: None,
            reading: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Height above mean sea level, m.
    pub height_m: f64,
    /// World horizontal position (x, z) of the camera, m. Geometry is built relative to it.
    pub position_m: [f64; 2],
    /// Image width in pixels (the full 360 degree width for the equirectangular camera).
    pub width: usize,
    /// Width / height of a pinhole image.
    pub aspect: f64,
    pub projection: Projection,
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            height_m: 2.0,
            position_m: [0.0, 0.0],
            width: 2048,
            aspect: 16.0 / 9.0,
            projection: Projection::Equirect { band_deg: None },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SkyConfig {
    /// Equirectangular EXR sky map; relative paths are taken from the config file's folder.
    /// Without one, `analytic` lights the scene.
    pub file: Option<PathBuf>,
    pub analytic: AnalyticSky,
    /// Sky dome altitude, m (the paper: 200 km); absent = at infinity.
    pub dome_altitude_m: Option<f64>,
    pub scale: f32,
}

impl Default for SkyConfig {
    fn default() -> Self {
        SkyConfig {
            file: None,
            analytic: AnalyticSky::default(),
            dome_altitude_m: Some(200_000.0),
            scale: 1.0,
        }
    }
}

/// Which BVH traces the scene: Embree when this build has it, else the Rust BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Debian's Embree through the C shim.
    Embree,
    /// The pure-Rust BVH (src/accel/bvh.rs).
    Rust,
}

impl Default for Backend {
    fn default() -> Self {
        if cfg!(feature = "embree") {
            Backend::Embree
        } else {
            Backend::Rust
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    pub spp: u32,
    /// Seed of the Monte Carlo samples.
    pub seed: u64,
    /// Seed of the ocean: which realization of the sea state (kept apart from `seed`, so the
    /// same sea can be rendered with independent noise).
    pub ocean_seed: u64,
    /// Worker threads for tessellation, Embree and tracing (0 = all cores).
    pub threads: usize,
    pub normals: NormalMode,
    pub max_segments: u32,
    pub branch_depth: u32,
    pub backend: Backend,
}

impl Default for RenderConfig {
    fn default() -> Self {
        let t = TraceSettings::default();
        RenderConfig {
            spp: 16,
            seed: 1,
            ocean_seed: 1,
            threads: 0,
            normals: t.normals,
            max_segments: t.max_segments,
            branch_depth: t.branch_depth,
            backend: Backend::default(),
        }
    }
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SceneConfig {
    pub ocean: OceanParams,
    pub lod: LodConfig,
    pub camera: CameraConfig,
    pub sky: SkyConfig,
    pub water: Water,
    pub render: RenderConfig,
}

fn positive(field: &str, v: f64) -> Result<(), ConfigError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, "finite and > 0", v))
    }
}

impl SceneConfig {
    /// Reads a TOML scene; a relative sky file is resolved against the file's folder.
    pub fn load(path: &Path) -> Result<SceneConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.into(),
            source,
        })?;
        let mut cfg: SceneConfig = toml::from_str(&text).map_err(|e| ConfigError::Parse {
            path: path.into(),
            message: e.to_string(),
        })?;
        if let (Some(f), Some(dir)) = (&cfg.sky.file, path.parent())
            && f.is_relative()
        {
            cfg.sky.file = Some(dir.join(f));
        }
        Ok(cfg)
    }

    /// Checks every section; the first problem is returned with its field name.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.ocean.validate()?;
        let c = &self.camera;
        positive("camera.height_m", c.height_m)?;
        if !c.position_m.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                "camera.position_m",
                "finite",
                format!("{:?}", c.position_m),
            ));
        }
        if !(2..=65_536).contains(&c.width) {
            return Err(invalid("camera.width", "in 2..=65536", c.width));
        }
        positive("camera.aspect", c.aspect)?;
        match c.projection {
            Projection::Equirect {
                band_deg: Some((top, bottom)),
            } => {
                if !(top.is_finite()
                    && bottom.is_finite()
                    && (-90.0..=90.0).contains(&top)
                    && (-90.0..=90.0).contains(&bottom)
                    && top > bottom)
                {
                    return Err(invalid(
                        "camera.projection.band_deg",
                        "(top, bottom) with 90 >= top > bottom >= -90",
                        format!("({top}, {bottom})"),
                    ));
                }
            }
            Projection::Pinhole {
                hfov_deg,
                yaw_deg,
                pitch_deg,
            } => {
                if !(hfov_deg > 0.0 && hfov_deg < 179.0) {
                    return Err(invalid(
                        "camera.projection.hfov_deg",
                        "in (0, 179)",
                        hfov_deg,
                    ));
                }
                if !yaw_deg.is_finite() || !(-90.0..=90.0).contains(&pitch_deg) {
                    return Err(invalid(
                        "camera.projection",
                        "finite yaw and pitch in [-90, 90]",
                        format!("yaw {yaw_deg}, pitch {pitch_deg}"),
                    ));
                }
            }
            Projection::Equirect { band_deg: None } => {}
        }
        if let Some(a) = self.sky.dome_altitude_m {
            positive("sky.dome_altitude_m", a)?;
        }
        if !(self.sky.scale >= 0.0 && self.sky.scale.is_finite()) {
            return Err(invalid("sky.scale", "finite and >= 0", self.sky.scale));
        }
        let w = &self.water;
        if !(w.ior >= 1.0 && w.ior.is_finite()) {
            return Err(invalid("water.ior", "finite and >= 1", w.ior));
        }
        for (name, v) in [
            ("water.absorption", w.absorption),
            ("water.upwelling_rrs", w.upwelling_rrs),
        ] {
            if !v.iter().all(|x| x.is_finite() && *x >= 0.0) {
                return Err(invalid(name, "finite and >= 0", format!("{v:?}")));
            }
        }
        let r = &self.render;
        if !(1..=1_000_000).contains(&r.spp) {
            return Err(invalid("render.spp", "in 1..=1000000", r.spp));
        }
        if !(1..=64).contains(&r.max_segments) {
            return Err(invalid("render.max_segments", "in 1..=64", r.max_segments));
        }
        if r.branch_depth > r.max_segments.min(16) {
            return Err(invalid(
                "render.branch_depth",
                "at most max_segments and 16 (each level doubles the rays)",
                r.branch_depth,
            ));
        }
        self.lod_params()?.validate()?;
        Ok(())
    }

    /// The LOD parameters this scene asks for. The pattern follows the camera: all directions
    /// for the 360 degree camera, only the field of view for a pinhole (skip what is not seen).
    pub fn lod_params(&self) -> Result<LodParams, ConfigError> {
        let h = self.camera.height_m;
        let l = &self.lod;
        let mut p = match l.preset {
            LodChoice::PaperHigh => Preset::PaperHigh.params(h),
            LodChoice::PaperLow => Preset::PaperLow.params(h),
            LodChoice::Auto => LodParams::auto(h, self.camera.width as u32),
            LodChoice::Custom => {
                let need = |v: Option<f64>, f: &str| {
                    v.ok_or_else(|| invalid(f, "set when lod.preset = \"custom\"", "nothing"))
                };
                LodParams {
                    near_size_m: need(l.near_size_m, "lod.near_size_m")?,
                    double_distance_m: need(l.double_distance_m, "lod.double_distance_m")?,
                    ..Preset::PaperLow.params(h)
                }
            }
        };
        if let Some(v) = l.near_size_m {
            p.near_size_m = v;
        }
        if let Some(v) = l.double_distance_m {
            p.double_distance_m = v;
        }
        if l.generations.is_some() {
            p.generations = l.generations;
        }
        if l.max_distance_m.is_some() {
            p.max_distance_m = l.max_distance_m;
        }
        if let Some(r) = l.reading {
            p.reading = r;
        }
        if let Projection::Pinhole {
            hfov_deg, yaw_deg, ..
        } = self.camera.projection
        {
            // The frustum pattern culls on the horizontal field of view; a wide image's diagonal
            // reaches further sideways than hfov, which the pattern's own margin covers.
            p.pattern = Pattern::Frustum { yaw_deg, hfov_deg };
        }
        Ok(p)
    }

    /// The integrator's settings under a sky of downwelling irradiance `sky_irradiance`.
    pub fn trace_settings(&self, sky_irradiance: glam::Vec3) -> TraceSettings {
        TraceSettings {
            normals: self.render.normals,
            max_segments: self.render.max_segments,
            branch_depth: self.render.branch_depth,
            water: self.water,
            upwelling: self.water.upwelling(sky_irradiance).to_array(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_round_trip_through_toml() {
        let c = SceneConfig::default();
        c.validate().unwrap();
        let text = toml::to_string(&c).unwrap();
        let back: SceneConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn unknown_keys_and_bad_values_name_the_field() {
        let e = toml::from_str::<SceneConfig>("[camera]\nheigth_m = 2\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("heigth_m"), "{e}");
        let c: SceneConfig = toml::from_str("[camera]\nheight_m = -2\n").unwrap();
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "camera.height_m must be finite and > 0 (got -2)"
        );
        let c: SceneConfig = toml::from_str("[render]\nspp = 0\n").unwrap();
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .starts_with("render.spp")
        );
        let c: SceneConfig = toml::from_str("[lod]\npreset = \"custom\"\n").unwrap();
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .starts_with("lod.near_size_m")
        );
        let c: SceneConfig =
            toml::from_str("[camera.projection]\nkind = \"equirect\"\nband_deg = [-6.0, 1.0]\n")
                .unwrap();
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .starts_with("camera.projection.band_deg")
        );
    }

    #[test]
    fn pinhole_camera_gets_the_frustum_pattern() {
        let c: SceneConfig = toml::from_str("[camera.projection]\nkind = \"pinhole\"\nhfov_deg = 60.0\nyaw_deg = 30.0\npitch_deg = -5.0\n").unwrap();
        c.validate().unwrap();
        assert_eq!(
            c.lod_params().unwrap().pattern,
            Pattern::Frustum {
                yaw_deg: 30.0,
                hfov_deg: 60.0
            }
        );
    }
}
