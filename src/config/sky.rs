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
    /// A clear sky: blue zenith brightening towards a hazy horizon, a glow around the sun and a
    /// 0.53 degree sun disc. A simple empirical model, not a spectral one (see the skies issue).
    Clear {
        #[serde(default = "clear::sun_elevation_deg")]
        sun_elevation_deg: f32,
        #[serde(default = "clear::sun_azimuth_deg")]
        sun_azimuth_deg: f32,
        #[serde(default = "clear::sun_radiance")]
        sun_radiance: f32,
        #[serde(default = "clear::sky_scale")]
        sky_scale: f32,
    },
}

/// The clear sky's defaults, key by key (every key of a scene file is optional).
mod clear {
    pub fn sun_elevation_deg() -> f32 {
        4.0
    }
    pub fn sun_azimuth_deg() -> f32 {
        180.0
    }
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
            sun_radiance: clear::sun_radiance(),
            sky_scale: clear::sky_scale(),
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
    /// Sky dome altitude, m (the paper: 200 km); absent = at infinity.
    pub dome_altitude_m: Option<f64>,
    pub scale: f32,
    /// Clip a sky map as a photograph clips the sun: texels brighter (in luminance) than
    /// `clip_relative` times the median luminance of the map above the horizon are scaled down
    /// to it. Absent = the map as it is. (The paper's skies were photographs with clipped suns.)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip_relative: Option<f32>,
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
