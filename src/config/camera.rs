//! The camera: where it stands, how wide its image is, and its projection (the paper's
//! equirectangular 360-degree camera, optionally limited to an elevation band, or a pinhole).

use serde::{Deserialize, Serialize};

/// Which camera and its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Projection {
    /// Full sphere; `band_deg = Some((top, bottom))` renders only elevations from `top` down to
    /// `bottom` degrees (e.g. (1, -6)) at the full-sphere pixel pitch.
    Equirect { band_deg: Option<(f64, f64)> },
    /// Pinhole with horizontal field of view, looking at azimuth `yaw_deg`, elevation `pitch_deg`.
    Pinhole {
        hfov_deg: f64,
        yaw_deg: f64,
        pitch_deg: f64,
    },
}

/// The camera section of a scene.
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
