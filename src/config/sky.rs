//! The sky section of a scene: a sky map file or a built-in analytic sky, the dome's altitude
//! and a radiance scale (the paper lights its scenes with 360-degree sky maps only, section 5).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// A built-in sky that needs no file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum AnalyticSky {
    /// The same radiance in every direction (white furnace tests).
    Uniform { radiance: [f32; 3] },
    /// Linear in sin(elevation) from `horizon` (and below) to `zenith`.
    Gradient { zenith: [f32; 3], horizon: [f32; 3] },
    /// The clear sky of Preetham, Shirley & Smits 1999 ("A Practical Analytic Model for
    /// Daylight"), evaluated per ray, with its 0.53 degree sun disc at the radiance that model's
    /// atmosphere transmits: the model `sky generate --kind clear` renders into maps, in the
    /// same units (1e5 cd/m^2).
    Clear {
        #[serde(default = "clear::sun_elevation_deg")]
        sun_elevation_deg: f32,
        #[serde(default = "clear::sun_azimuth_deg")]
        sun_azimuth_deg: f32,
        /// Atmospheric turbidity (2 very clear ... 6 hazy; the model's fit holds for 1.7..=10).
        #[serde(default = "clear::turbidity")]
        turbidity: f32,
    },
    /// A hand-made clear sky, no physical model behind it: blue zenith brightening towards a
    /// hazy horizon, a glow around the sun and a sun disc of any radiance. Kept for the
    /// benchmarks measured under it and for scenes that want a sun of a chosen brightness.
    HandMadeClear {
        #[serde(default = "clear::sun_elevation_deg")]
        sun_elevation_deg: f32,
        #[serde(default = "clear::sun_azimuth_deg")]
        sun_azimuth_deg: f32,
        #[serde(default = "hand_made::sun_radiance")]
        sun_radiance: f32,
        #[serde(default = "hand_made::sky_scale")]
        sky_scale: f32,
    },
}

/// The clear skies' defaults, key by key (every key of a scene file is optional): the sun of
/// the default scene, 3 degrees up at azimuth 180 (towards -x), under the turbidity of the
/// shipped maps.
mod clear {
    pub fn sun_elevation_deg() -> f32 {
        3.0
    }
    pub fn sun_azimuth_deg() -> f32 {
        180.0
    }
    pub fn turbidity() -> f32 {
        2.5
    }
}

/// The hand-made clear sky's own defaults.
mod hand_made {
    pub fn sun_radiance() -> f32 {
        2000.0
    }
    pub fn sky_scale() -> f32 {
        1.0
    }
}

impl Default for AnalyticSky {
    /// A low sun, where the paper found normal mapping matters most.
    fn default() -> Self {
        AnalyticSky::Clear {
            sun_elevation_deg: clear::sun_elevation_deg(),
            sun_azimuth_deg: clear::sun_azimuth_deg(),
            turbidity: clear::turbidity(),
        }
    }
}

/// The sky section of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SkyConfig {
    /// Equirectangular EXR sky map; relative paths are taken from the config file's folder.
    /// Without one, `analytic` lights the scene.
    pub file: Option<PathBuf>,
    pub analytic: AnalyticSky,
    /// Sky dome altitude, m (the paper: 200 km); `None` = at infinity, written `inf` in a file.
    #[serde(with = "dome_altitude")]
    pub dome_altitude_m: Option<f64>,
    pub scale: f32,
    /// Clip the sky as a photograph clips the sun: radiance brighter (in luminance) than
    /// `clip_relative` times the median luminance above the horizon is scaled down to it (a
    /// map's texels, or the built-in sky ray by ray). Absent = the sky as it is. (The paper's
    /// skies were photographs with clipped suns.)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip_relative: Option<f32>,
}

/// `sky.dome_altitude_m` in a file: metres, or TOML's `inf` for a sky at infinity, written back
/// the same way (a left-out key is the 200 km default, so `None` needs a spelling of its own).
mod dome_altitude {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(v.unwrap_or(f64::INFINITY))
    }

    /// `inf` and JSON's `null` (which is what serde_json writes for an infinity: pass files
    /// carry the scene) are a sky at infinity.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        let v = Option::<f64>::deserialize(d)?;
        Ok(v.filter(|&v| v != f64::INFINITY))
    }
}

impl Default for SkyConfig {
    fn default() -> Self {
        SkyConfig {
            file: None,
            analytic: AnalyticSky::default(),
            dome_altitude_m: Some(200_000.0),
            scale: 1.0,
            clip_relative: None,
        }
    }
}
