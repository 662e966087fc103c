//! Ray footprints as ray cones (Akenine-Moller, Crassin, Boksansky, Belcour, Panteleev, Wright
//! 2021, "Improved shader and texture level of detail using ray cones"): a camera ray starts
//! as a cone of zero width spreading by the angle one pixel spans, and its width at a hit is
//! the width it left with plus the spread times the distance. Rays leaving a hit keep the
//! camera's spread.
//!
//! The surface's curvature, which widens a cone reflected off a crest and narrows one off a
//! trough, is left out, and so is a rough hit's own lobe: both would only widen the cones, so
//! without them fewer waves are filtered than could be, never more (a narrower cone keeps more
//! of the waves as mapped normals, with their noise, and leaves less to the Gaussian lobe,
//! whose model of the waves it takes is what a wider filter pays in accuracy). The width is
//! the cone's, across the ray: where it meets the sea at a grazing angle its footprint is
//! longer along the ray, and the split takes the shorter axis, so again the waves it treats as
//! unresolved are below the footprint both ways.
//!
//! The lobe must not take a wave the geometry holds: where a ray lands on a mesh finer than
//! its footprint depends on the facets it can see, and the mapped normal there follows them
//! ([`mesh_sigma`]).

use super::camera::Camera;
use super::integrator::TraceSettings;
use crate::config::Projection;

/// The share of its slope power that the shortest wave a mesh's triangles can hold (two grid
/// spacings long) keeps through a footprint of [`mesh_sigma`]: a judgement, of how little of a
/// wave the geometry follows may go to the lobe.
pub const MESH_KEEPS: f32 = 0.99;

/// The largest footprint std, m, that leaves to the lobe no wave the triangle of nominal
/// corners `uv` can hold: a Gaussian of this std keeps [`MESH_KEEPS`] of the slope power of
/// a wave two grid spacings long (the spacing sqrt(2 x area), a grid cell's side for the
/// doubling tessellation's half cells). On a mesh coarser than the pixel it does not bind; on
/// one that holds the waves below the pixel (paper-high) a lobe that took them, drawn by area
/// on the sea, would lose the facets' own visibility: measured there, 10.5 % darker than the
/// mapped render near the horizon.
#[inline]
pub fn mesh_sigma(uv: [[f32; 2]; 3]) -> f32 {
    let [a, b, c] = uv;
    let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    let spacing = (2.0 * area).sqrt();
    spacing * (-MESH_KEEPS.ln()).sqrt() / std::f32::consts::PI
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mesh_footprint_keeps_the_shortest_wave_its_triangles_hold() {
        // Half cells of a grid of spacing e, either way round and anywhere: a Gaussian of the
        // std mesh_sigma gives keeps MESH_KEEPS of the slope power of a wave 2 e long.
        for (e, at) in [
            (0.9f32, [0.0f32, 0.0]),
            (0.03, [512.25, -7.5]),
            (14.4, [-3e3, 2e3]),
        ] {
            let [x, z] = at;
            for tri in [
                [[x, z], [x + e, z], [x, z + e]],
                [[x + e, z + e], [x, z + e], [x + e, z]],
            ] {
                let sigma = mesh_sigma(tri);
                let k = std::f32::consts::PI / e;
                let kept = (-(k * sigma).powi(2)).exp();
                assert!((kept - MESH_KEEPS).abs() < 1e-4, "{e} at {at:?}: {kept}");
            }
        }
    }
}
