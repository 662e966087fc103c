//! Camera rays into the path tracer: the triangle a pixel's steep rays are predicted to hit,
//! the surface each path meets on the exact surface of a filtered render, and a pixel's batch
//! of camera rays handed to [`SceneRef::radiance_batch`].

use glam::Vec3;

use super::counters::Counters;
use super::footprint;
use super::integrator::{CAMERA_BATCH, PathVertex, SceneRef, TraceSettings};
#[cfg(doc)]
use super::shortcuts::{hit_on_triangle, max_slope};
use crate::accel::Ray;
use crate::config::NormalMode;
use crate::ocean::slopes::{ALL_WAVES, LevelSet};
use crate::rng::Rng;

impl SceneRef<'_> {
    /// Whether a ray descends more steeply than any slope of the mesh ([`max_slope`]): along
    /// it the height above the surface only falls, so it crosses the surface at most once.
    #[inline]
    pub fn descends_steeply(&self, d: Vec3) -> bool {
        self.skip_slope
            .is_some_and(|slope| d.y < 0.0 && -d.y > slope * (d.x * d.x + d.z * d.z).sqrt())
    }

    /// The triangle a pixel's camera rays are predicted to hit: the one its centre ray `ray`
    /// hits, when that ray descends more steeply than the mesh ever slopes (`None` otherwise,
    /// for a miss, and when `predict_camera_hits` is off). A camera ray that descends as
    /// steeply crosses the surface at most once, so a hit on this triangle is its closest hit
    /// (up to rounding): the BVH need not be searched ([`Self::radiance_camera_batch`]). The
    /// centre ray depends on the pixel alone, so a sample's hit does not depend on which other
    /// samples a render or a pass takes.
    pub fn predict_camera_prim(&self, ray: &Ray, c: &mut Counters) -> Option<u32> {
        if !self.predict_camera_hits
            || !self.descends_steeply(Vec3::from(ray.dir))
            || !ray.is_finite()
        {
            return None;
        }
        c.prediction_rays += 1;
        self.accel.intersect(ray).map(|h| h.prim)
    }

    /// Whether paths meet the exact surface of the waves their footprints resolve: filtered
    /// normals on the exact surface.
    pub(super) fn exact_lods(&self, settings: &TraceSettings) -> bool {
        settings.normals == NormalMode::Filtered
            && self.slopes.is_some()
            && self.accel.exact_surface()
    }

    /// The surface a camera ray's path meets ([`Self::exact_lods`]; every wave otherwise):
    /// the levels of the footprint where the ray meets the mean sea (the earth's sphere; where
    /// it passes above it, at its closest approach), one of each layer's two drawn with the
    /// blend's weight by a number from the path's `rng`
    /// ([`crate::ocean::slopes::SurfaceSlopes::drawn_levels`]).
    /// The hit itself lies a wave's height nearer or farther, where the footprint is that much
    /// narrower or wider. Its later segments keep it: a ray leaving a hit starts on that
    /// surface, and another surface would lie above or below its origin.
    fn camera_lod(&self, ray: &Ray, settings: &TraceSettings, rng: &mut Rng) -> LevelSet {
        let Some(slopes) = self.slopes.filter(|_| self.exact_lods(settings)) else {
            return ALL_WAVES;
        };
        let r = self.earth_radius_m;
        let [ox, oy, oz] = ray.org.map(f64::from);
        let d = Vec3::from(ray.dir).normalize_or(Vec3::NEG_Y).as_dvec3();
        // |o + t d - c| = r, c the sphere's centre (0, -r, 0): t^2 + 2 b t + q = 0
        let b = ox * d.x + (oy + r) * d.y + oz * d.z;
        let q = ox * ox + oz * oz + oy * (oy + 2.0 * r);
        let disc = b * b - q;
        let t = if disc >= 0.0 { -b - disc.sqrt() } else { -b };
        let sigma = footprint::width_at(0.0, settings, t.max(0.0) as f32) * settings.filter_width;
        slopes.drawn_levels(sigma, rng.f32())
    }

    /// Whether every camera ray of a batch sees the sky and nothing else, as
    /// [`Self::radiance_batch`] would answer it: it rises above the sea
    /// ([`Self::rises_above_the_sea`], the test `answer_untraced` makes), no object can be in
    /// its way, and the path may take a segment. The sun it meets counts whole (a camera ray
    /// carries no sun density), and the random numbers its path would have drawn (the exact
    /// surface's levels) are drawn by no one else.
    fn sees_only_sky(&self, rays: &[Ray], settings: &TraceSettings) -> bool {
        settings.max_segments > 0
            && rays.iter().all(|r| self.rises_above_the_sea(r))
            && self
                .objects
                .is_none_or(|o| !rays.iter().any(|r| o.may_hit(r)))
    }

    /// Radiance along camera rays (in the air, first segment), computed together: see
    /// [`Self::radiance_batch`]. At most [`CAMERA_BATCH`] rays; `draws[i]`, if given, the two
    /// numbers ray i's first rough hit draws its normal with (the film's stratified pairs,
    /// [`super::strata`]); `rngs[i]` is ray i's generator
    /// and `out[i]` receives its radiance. `predicted`: the pixel's triangle from
    /// [`Self::predict_camera_prim`]; a ray that descends more steeply than the mesh slopes and
    /// meets it takes that hit ([`hit_on_triangle`]) instead of the BVH's. Each ray's result is
    /// bit for bit what it gets in a batch of one with the same prediction and draw; without
    /// draws and with no prediction, what [`Self::radiance`] gives it (with a prediction, that
    /// up to the rounding of the hit).
    #[allow(clippy::too_many_arguments)]
    pub fn radiance_camera_batch(
        &self,
        rays: &[Ray],
        draws: Option<&[[f32; 2]]>,
        predicted: Option<u32>,
        settings: &TraceSettings,
        rngs: &mut [Rng],
        c: &mut Counters,
        out: &mut [Vec3],
    ) {
        let n = rays.len();
        assert!(n <= CAMERA_BATCH && rngs.len() == n && out.len() == n);
        assert!(draws.is_none_or(|d| d.len() == n), "one draw per ray");
        if self.sees_only_sky(rays, settings) {
            // What the batch's stages would find for each ray, without them: a panorama's
            // upper half is all such batches.
            c.skipped_above += n as u64;
            let (mut orgs, mut dirs) = ([Vec3::ZERO; CAMERA_BATCH], [Vec3::ZERO; CAMERA_BATCH]);
            for ((o, d), ray) in orgs.iter_mut().zip(&mut dirs).zip(rays) {
                (*o, *d) = (ray.org.into(), ray.dir.into());
            }
            self.sky.radiance_many(&orgs[..n], &dirs[..n], out);
            return;
        }
        let mut entries = [PathVertex::NONE; CAMERA_BATCH];
        for (i, ((e, ray), rng)) in entries
            .iter_mut()
            .zip(rays)
            .zip(rngs.iter_mut())
            .enumerate()
        {
            let draw = draws.map(|d| d[i]);
            *e = PathVertex::camera(*ray, i as u8, self.camera_lod(ray, settings, rng), draw);
        }
        self.radiance_batch(&entries[..n], predicted, 0, settings, rngs, c, out);
    }
}
