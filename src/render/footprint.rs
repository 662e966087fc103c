//! Ray footprints as ray cones (Akenine-Moller, Crassin, Boksansky, Belcour, Panteleev, Wright
//! 2021, "Improved shader and texture level of detail using ray cones"): a camera ray starts
//! as a cone of zero width spreading by the angle one pixel spans, and its width at a hit is
//! the width it left with plus the spread times the distance. Rays leaving a hit keep the
//! camera's spread.
//!
//! The surface's curvature, which widens a cone reflected off a crest and narrows one off a
//! trough, is left out, and so is a rough hit's own lobe: both would only widen the cones, so
//! without them fewer waves are filtered than could be, never more (filtered normals converge
//! to the same image whatever the width; a narrower cone only keeps more of the waves as
//! mapped normals, with their noise). The width is the cone's, across the ray: where it meets
//! the sea at a grazing angle its footprint is longer along the ray, and the split takes the
//! shorter axis, so again the waves it treats as unresolved are below the footprint both ways.

use super::camera::Camera;
use super::integrator::TraceSettings;
use crate::config::Projection;

/// The width of a ray's cone `t` metres from an origin where it was `width0_m` across.
#[inline]
pub fn width_at(width0_m: f32, settings: &TraceSettings, t: f32) -> f32 {
    width0_m + settings.pixel_spread_rad * t
}

impl Camera {
    /// The angle one pixel spans, radians: the equirectangular camera's rows are 2 pi / width
    /// apart (its pixels are square in angle at the horizon); the pinhole's centre pixel spans
    /// its horizontal field over its width.
    pub fn pixel_spread_rad(&self) -> f32 {
        match self.projection {
            Projection::Equirect { .. } => std::f32::consts::TAU / self.width as f32,
            Projection::Pinhole { hfov_deg, .. } => {
                2.0 * (0.5 * hfov_deg.to_radians() as f32).tan() / self.width as f32
            }
        }
    }
}
