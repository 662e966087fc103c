//! The scene description: one TOML file (or the defaults) holding the ocean case, the LOD
//! tessellation, the camera, the sky, the water and the render settings, and its validation.
//! Plain data at the bottom of the crate: it imports no stage; the stages read what they need
//! from it. Unknown keys are errors, and every error names the offending field as it is
//! spelled in the file (e.g. `camera.height_m must be finite and > 0 (got -2)`).
//!
//! Enums that are spelled as text (in files and on the command line) implement [`Choice`]:
//! one list of names serves serde, `FromStr`, `Display` and the command line's possible values.

pub mod camera;
pub mod lod;
pub mod objects;
pub mod ocean;
pub mod render;
pub mod sky;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use camera::{CameraConfig, Mount, Projection};
pub use lod::{LodChoice, LodConfig, Pattern, Reading};
pub use objects::{Material, ObjectConfig, ShipConfig};
pub use ocean::OceanParams;
pub use render::{
    Aov, Backend, EmbreeGeometry, ExrCompression, FilterLobe, NormalMode, RenderConfig,
    SurfaceKind, Water, WrongSide,
};
pub use sky::{AnalyticSky, SkyConfig};

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
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
}

pub(crate) fn invalid(field: &str, requirement: &str, got: impl std::fmt::Display) -> ConfigError {
    ConfigError::Invalid {
        field: field.into(),
        requirement: requirement.into(),
        got: compact_number(got.to_string()),
    }
}

/// A number as a person reads it in a message: `1e300` and `1e-9`, not the 301 digits or the
/// nine zeros that Rust's `Display` of an f64 prints. Text that is not one number passes as is.
pub fn compact_number(text: String) -> String {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && text.len() > 8 => {
            let short = format!("{v:e}");
            if 2 * short.len() < text.len() {
                short
            } else {
                text
            }
        }
        _ => text,
    }
}

/// The largest radiance any input may hold (sky maps times their scale, analytic skies),
/// W m^-2 sr^-1 (or whatever unit the sky is in): a sample's square, which the per-pixel variance
/// takes and stores as f32 (at most 3.4e38), then stays finite, and so do all sums over samples
/// (f64). A real sun is about 2e7.
pub const MAX_RADIANCE: f64 = 1e18;

/// Checks a radiance-like input: finite, >= 0 and at most [`MAX_RADIANCE`].
pub fn check_radiance(field: &str, v: f64) -> Result<(), ConfigError> {
    if v.is_finite() && (0.0..=MAX_RADIANCE).contains(&v) {
        Ok(())
    } else {
        Err(invalid(field, "finite, >= 0 and <= 1e18", v))
    }
}

/// Most worker threads a job may ask for: 4 per core (more only adds scheduling and memory; at
/// thousands the thread start-up alone takes minutes), and at most 1024.
pub fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (4 * cores).min(1024)
}

/// Checks a thread count (0 = all cores) against [`max_threads`].
pub fn check_threads(field: &str, n: usize) -> Result<(), ConfigError> {
    let max = max_threads();
    if n <= max {
        Ok(())
    } else {
        Err(invalid(
            field,
            &format!("at most {max} (4 per core of this machine, at most 1024; 0 = all cores)"),
            n,
        ))
    }
}

pub(crate) fn positive(field: &str, v: f64) -> Result<(), ConfigError> {
    // NaN is not finite.
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, "finite and > 0", v))
    }
}

/// An enum spelled as text: its names in declaration order. `FromStr` and `Display` use them,
/// and so does serde (a test checks that they agree).
pub trait Choice:
    Copy + PartialEq + std::fmt::Display + std::str::FromStr<Err = String> + 'static
{
    const ALL: &'static [Self];
    fn name(self) -> &'static str;
    /// The names, comma-separated, for messages.
    fn names() -> String {
        Self::ALL
            .iter()
            .map(|v| v.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Implements [`Choice`], `Display` and `FromStr` for a fieldless enum from `Variant => "name"`
/// pairs, and an inherent `ALL`.
macro_rules! choice {
    ($t:ident { $($v:ident => $n:literal),+ $(,)? }) => {
        impl $t {
            pub const ALL: &'static [$t] = &[$($t::$v),+];
        }
        impl $crate::config::Choice for $t {
            const ALL: &'static [$t] = $t::ALL;
            fn name(self) -> &'static str {
                match self {
                    $($t::$v => $n),+
                }
            }
        }
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::config::Choice::name(*self))
            }
        }
        impl std::str::FromStr for $t {
            type Err = String;
            fn from_str(s: &str) -> Result<$t, String> {
                use $crate::config::Choice;
                $t::ALL
                    .iter()
                    .copied()
                    .find(|v| v.name() == s)
                    .ok_or_else(|| format!("`{s}` is not one of: {}", $t::names()))
            }
        }
    };
}
pub(crate) use choice;

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
    /// Objects on the sea (`[[object]]`), none by default.
    #[serde(rename = "object", skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectConfig>,
}

impl SceneConfig {
    /// Reads a TOML scene (`-`: from stdin); a relative sky file is resolved against the file's
    /// folder (stdin's: the working directory).
    pub fn load(path: &Path) -> Result<SceneConfig, ConfigError> {
        let from_stdin = path == Path::new("-");
        let text = if from_stdin {
            std::io::read_to_string(std::io::stdin())
        } else {
            std::fs::read_to_string(path)
        }
        .map_err(|source| ConfigError::Read {
            path: path.into(),
            source,
        })?;
        let shown = if from_stdin {
            Path::new("<stdin>")
        } else {
            path
        };
        let parse_error = |e: toml::de::Error| ConfigError::Parse {
            path: shown.into(),
            message: e.to_string(),
        };
        let mut cfg: SceneConfig = toml::from_str(&text).map_err(parse_error)?;
        // A preset sets the sea's explicit keys; a file that gives one beside it is ambiguous.
        if let Some(preset) = cfg.ocean.preset() {
            let table: toml::Table = text.parse().map_err(parse_error)?;
            let given = table.get("ocean").and_then(|o| o.as_table());
            if let Some(key) = ocean::sea_state::PRESET_KEYS
                .iter()
                .find(|k| given.is_some_and(|o| o.contains_key(**k)))
            {
                return Err(invalid(
                    &format!("ocean.{key}"),
                    &format!("left out beside {preset}, which sets it (keep one)"),
                    given
                        .and_then(|o| o.get(*key))
                        .map_or(String::new(), |v| v.to_string()),
                ));
            }
            cfg.ocean.apply_preset();
            // a preset's sea chooses its layers unless the file names them
            if !given.is_some_and(|o| o.contains_key("layers")) {
                cfg.ocean.layers_auto = true;
            }
        }
        cfg.ocean.resolve_layers();
        // A file's relative paths are relative to the file; stdin's to the working directory.
        if let (Some(f), Some(dir), false) = (&cfg.sky.file, path.parent(), from_stdin)
            && f.is_relative()
        {
            cfg.sky.file = Some(dir.join(f));
        }
        if let (Some(dir), false) = (path.parent(), from_stdin) {
            for o in &mut cfg.objects {
                if !o.is_built_in_ship() && o.mesh.is_relative() {
                    o.mesh = dir.join(&o.mesh);
                }
            }
        }
        Ok(cfg)
    }

    /// The scene as TOML that [`SceneConfig::load`] reads back to the same scene from any
    /// folder: every key written out, the sky map's path made absolute.
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        let mut c = self.clone();
        // the preset's sea is written out key by key, its swell too (a file with both a preset
        // and the keys it sets is refused)
        (c.ocean.beaufort, c.ocean.douglas) = (None, None);
        if let Some(f) = &c.sky.file {
            c.sky.file = Some(std::path::absolute(f).unwrap_or_else(|_| f.clone()));
        }
        for o in &mut c.objects {
            if !o.is_built_in_ship() {
                o.mesh = std::path::absolute(&o.mesh).unwrap_or_else(|_| o.mesh.clone());
            }
        }
        toml::to_string(&c)
    }

    /// Checks every section field by field; the first problem is returned with its field name.
    /// (Whether the tessellation's sizes fit together once a preset's defaults are merged in is
    /// the tessellator's check, `crate::lod::params_for`.)
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.ocean.validate()?;
        self.lod.validate()?;
        self.camera.validate()?;
        self.sky.validate()?;
        for (i, o) in self.objects.iter().enumerate() {
            o.validate(&format!("object[{i}]"))?;
            let name = o.display_name(i);
            if let Some(j) = (0..i).find(|&j| self.objects[j].display_name(j) == name) {
                return Err(invalid(
                    &format!("object[{i}].name"),
                    &format!("a name no other object has (object[{j}] is called that too)"),
                    &name,
                ));
            }
        }
        if let Some(m) = &self.camera.mount {
            let names: Vec<String> = (self.objects.iter().enumerate())
                .map(|(k, o)| o.display_name(k))
                .collect();
            if !names.contains(&m.object) {
                return Err(invalid(
                    "camera.mount.object",
                    &format!("the name of an [[object]] (this scene has {names:?})"),
                    &m.object,
                ));
            }
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
        check_threads("render.threads", r.threads)?;
        if !(1..=1_000_000).contains(&r.spp) {
            return Err(invalid("render.spp", "in 1..=1000000", r.spp));
        }
        if !(r.filter_width > 0.0 && r.filter_width <= 16.0) {
            return Err(invalid(
                "render.filter_width",
                "in (0, 16] ray-cone widths",
                r.filter_width,
            ));
        }
        if !(1..=crate::render::MAX_SUN_SAMPLES).contains(&r.sun_samples) {
            return Err(invalid(
                "render.sun_samples",
                &format!("in 1..={}", crate::render::MAX_SUN_SAMPLES),
                r.sun_samples,
            ));
        }
        if let Some(e) = r.exposure
            && !(e.is_finite() && e.abs() <= render::MAX_EXPOSURE_STOPS)
        {
            return Err(invalid(
                "render.exposure",
                &format!("\"auto\" or stops within +-{}", render::MAX_EXPOSURE_STOPS),
                e,
            ));
        }
        if r.surface == render::SurfaceKind::Exact {
            if !matches!(
                r.normals,
                NormalMode::Mapped | NormalMode::Geometric | NormalMode::Filtered
            ) {
                return Err(invalid(
                    "render.normals",
                    "mapped, filtered or geometric with render.surface = \"exact\" (the \
                     layers' normal, or the surface's own tangent plane, at the point hit)",
                    r.normals,
                ));
            }
            if !matches!(
                self.ocean.interp,
                crate::ocean::Interp::Bilinear | crate::ocean::Interp::Prefiltered
            ) {
                return Err(invalid(
                    "ocean.interp",
                    "bilinear or prefiltered with render.surface = \"exact\" (the reads the \
                     surface's bounds cover)",
                    self.ocean.interp,
                ));
            }
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
        Ok(())
    }
}

impl SkyConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(a) = self.dome_altitude_m {
            positive("sky.dome_altitude_m", a)?;
        }
        if !(self.scale >= 0.0 && self.scale.is_finite()) {
            return Err(invalid("sky.scale", "finite and >= 0", self.scale));
        }
        if let Some(c) = self.clip_relative
            && !(c >= 1.0 && c.is_finite())
        {
            return Err(invalid("sky.clip_relative", "finite and >= 1", c));
        }
        let scale = self.scale as f64;
        let rgb = |field: &str, v: [f32; 3]| {
            v.iter()
                .try_for_each(|&c| check_radiance(field, c as f64 * scale.max(1.0)))
        };
        let check_sun = |elevation_deg: f32, azimuth_deg: f32| {
            crate::sky::check_sun_elevation(elevation_deg as f64)
                .map_err(|m| invalid("sky.analytic.sun_elevation_deg", &m, elevation_deg))?;
            if !azimuth_deg.is_finite() {
                return Err(invalid(
                    "sky.analytic.sun_azimuth_deg",
                    "finite",
                    azimuth_deg,
                ));
            }
            Ok(())
        };
        match self.analytic {
            AnalyticSky::Uniform { radiance } => rgb("sky.analytic.radiance", radiance)?,
            AnalyticSky::Gradient { zenith, horizon } => {
                rgb("sky.analytic.zenith", zenith)?;
                rgb("sky.analytic.horizon", horizon)?;
            }
            AnalyticSky::Clear {
                sun_elevation_deg,
                sun_azimuth_deg,
                turbidity,
            } => {
                check_sun(sun_elevation_deg, sun_azimuth_deg)?;
                let (lo, hi) = crate::sky::TURBIDITY_RANGE;
                if !(lo..=hi).contains(&(turbidity as f64)) {
                    return Err(invalid(
                        "sky.analytic.turbidity",
                        &format!("in [{lo}, {hi}], the range the model was fitted on"),
                        turbidity,
                    ));
                }
                // its brightest radiance is the sun's disc, below the sun outside the air
                check_radiance(
                    "sky.scale (times the clear sky's sun)",
                    crate::sky::procedural::SUN_LUMINANCE_EXTRATERRESTRIAL
                        / 1e3
                        / crate::sky::procedural::KCD_PER_UNIT
                        * scale,
                )?;
            }
            AnalyticSky::HandMadeClear {
                sun_elevation_deg,
                sun_azimuth_deg,
                sun_radiance,
                sky_scale,
            } => {
                check_sun(sun_elevation_deg, sun_azimuth_deg)?;
                check_radiance(
                    "sky.analytic.sun_radiance",
                    sun_radiance as f64 * scale.max(1.0),
                )?;
                check_radiance("sky.analytic.sky_scale", sky_scale as f64 * scale.max(1.0))?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_compact() {
        assert_eq!(compact_number(1e300.to_string()), "1e300");
        assert_eq!(compact_number(1e-9.to_string()), "1e-9");
        assert_eq!(compact_number(0.225.to_string()), "0.225");
        assert_eq!(compact_number(123456789.0.to_string()), "123456789");
        assert_eq!(compact_number("(5, 9)".into()), "(5, 9)");
        let e = invalid("ocean.rms_m", "at most 25", 1e300);
        assert!(e.to_string().ends_with("(got 1e300)"), "{e}");
    }

    #[test]
    fn defaults_are_valid_and_round_trip_through_toml() {
        let c = SceneConfig::default();
        c.validate().unwrap();
        let text = toml::to_string(&c).unwrap();
        let back: SceneConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, c);
        // A sky at infinity is written `inf` and read back as one.
        let mut c = SceneConfig::default();
        c.sky.dome_altitude_m = None;
        let text = c.to_toml().unwrap();
        assert!(text.contains("dome_altitude_m = inf"), "{text}");
        assert_eq!(toml::from_str::<SceneConfig>(&text).unwrap(), c);
        // JSON (a pass file's header) writes the infinity as null and reads it back.
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<SceneConfig>(&json).unwrap(), c);
        let c: SceneConfig = toml::from_str("[sky]\ndome_altitude_m = 5e4\n").unwrap();
        assert_eq!(c.sky.dome_altitude_m, Some(5e4));
        let c: SceneConfig = toml::from_str("[sky]\ndome_altitude_m = -inf\n").unwrap();
        assert!(c.validate().is_err());
        // The PNG's exposure: "auto" (the default) or stops, integer or not, in TOML and JSON.
        assert!(
            toml::to_string(&SceneConfig::default())
                .unwrap()
                .contains("exposure = \"auto\"")
        );
        for (text, stops) in [("2", Some(2.0)), ("-1.5", Some(-1.5)), ("\"auto\"", None)] {
            let c: SceneConfig = toml::from_str(&format!("[render]\nexposure = {text}\n")).unwrap();
            assert_eq!(c.render.exposure, stops);
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(serde_json::from_str::<SceneConfig>(&json).unwrap(), c);
        }
        let e = toml::from_str::<SceneConfig>("[render]\nexposure = \"bright\"\n").unwrap_err();
        assert!(e.to_string().contains("stops"), "{e}");
        let c: SceneConfig = toml::from_str("[render]\nexposure = 65\n").unwrap();
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .contains("render.exposure")
        );
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
        for k in [1, 16] {
            let c: SceneConfig = toml::from_str(&format!("[render]\nsun_samples = {k}\n")).unwrap();
            assert!(c.validate().is_ok(), "{k} sun samples");
        }
        for k in [0, 17] {
            let c: SceneConfig = toml::from_str(&format!("[render]\nsun_samples = {k}\n")).unwrap();
            assert_eq!(
                c.validate().unwrap_err().to_string(),
                format!("render.sun_samples must be in 1..=16 (got {k})")
            );
        }
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

    /// Serde's spelling of every variant is the one `Display` and `FromStr` use.
    fn names_agree<T: Choice + Serialize + serde::de::DeserializeOwned + std::fmt::Debug>() {
        for &v in T::ALL {
            let json = serde_json::to_value(v).unwrap();
            assert_eq!(json, serde_json::Value::String(v.name().into()), "{v:?}");
            assert_eq!(serde_json::from_value::<T>(json).unwrap(), v);
            assert!(v.name().parse::<T>().is_ok_and(|p| p == v));
        }
        assert!("nonsense".parse::<T>().unwrap_err().contains("nonsense"));
    }

    #[test]
    fn text_names_agree_with_serde() {
        names_agree::<LodChoice>();
        names_agree::<Reading>();
        names_agree::<NormalMode>();
        names_agree::<Backend>();
        names_agree::<WrongSide>();
        names_agree::<FilterLobe>();
        names_agree::<ocean::SpectrumKind>();
        names_agree::<ocean::SpreadingKind>();
        names_agree::<ocean::Interp>();
        assert_eq!(
            "paper-hi".parse::<LodChoice>().unwrap_err(),
            "`paper-hi` is not one of: paper-high, paper-low, auto, custom"
        );
    }
}
