//! Shading normals at a batch of hits: the interpolated vertex normals, the ocean's own
//! normals recomputed from the layers at the interpolated texture coordinate (paper section 4),
//! with the cost of the mapped normals measured as the render goes, or the surface's own
//! geometric normal.

use glam::Vec3;

use super::counters::Counters;
use super::earth_tilt::tilt_to_earth_many;
use super::integrator::{CAMERA_BATCH, SceneRef, TraceSettings};
use super::interface::surface_point;
use crate::accel::Hit;
use crate::config::NormalMode;
use crate::mesh::Mesh;
use crate::ocean::MAX_LAYERS;

impl SceneRef<'_> {
    /// The shading normals (air side up) at a batch of hits into `out` (a miss's entry is
    /// not used: left as it is, or +y).
    /// Mapped normals: each hit's texture coordinate, the ocean's normals there computed
    /// together ([`Sampler::normals`], bit for bit one at a time), tilted to the curved earth.
    /// Filtered normals: the same, each layer weighted by the share of its waves the hit's
    /// footprint (`widths[i]` metres across) resolves, and the slope covariance of the rest
    /// into `covs` ([`crate::ocean::slopes::SurfaceSlopes::split`]; left as it is for other modes).
    /// One call in 64 is timed alone, one timed with a second evaluation of the same normals
    /// (see [`Counters::normal_map_thread_seconds`]).
    pub(super) fn shading_normals(
        &self,
        hits: &[Option<Hit>],
        widths: &[f32],
        settings: &TraceSettings,
        c: &mut Counters,
        out: &mut [Vec3],
        covs: &mut [[f32; 3]],
    ) {
        debug_assert!(hits.len() <= CAMERA_BATCH && out.len() == hits.len());
        let mesh = self.accel.mesh();
        let filtered = settings.normals == NormalMode::Filtered;
        match (settings.normals, &self.ocean) {
            (NormalMode::Mapped | NormalMode::Filtered, Some(ocean)) => {
                let mut uv = [[0.0f32; 2]; CAMERA_BATCH];
                let mut at = [0u8; CAMERA_BATCH];
                let mut n = 0;
                for (i, h) in hits.iter().enumerate() {
                    if let Some(h) = h {
                        (uv[n], at[n]) = (self.accel.interpolate_uv(h), i as u8);
                        n += 1;
                    }
                }
                if n == 0 {
                    return;
                }
                let mut weights = [[1.0f32; MAX_LAYERS]; CAMERA_BATCH];
                // (Without the slope bands every wave counts as resolved: mapped normals.)
                if let Some(slopes) = self.slopes.filter(|_| filtered) {
                    for (j, &i) in at[..n].iter().enumerate() {
                        let sigma = widths[i as usize] * settings.filter_width;
                        let split = slopes.split(sigma);
                        weights[j] = split.weights;
                        covs[i as usize] = split.cov;
                    }
                }
                let mapped = |normals: &mut [Vec3]| {
                    let mut flat = [[0.0f32; 3]; CAMERA_BATCH];
                    if filtered {
                        ocean.normals_weighted(&uv[..n], &weights[..n], &mut flat[..n]);
                    } else {
                        ocean.normals(&uv[..n], &mut flat[..n]);
                    }
                    for (o, f) in normals.iter_mut().zip(&flat) {
                        *o = Vec3::from(*f);
                    }
                    tilt_to_earth_many(&uv[..n], self.earth_radius_m, normals);
                };
                // Neither timed call is a row's first (counters start afresh with every row),
                // whose cold caches would bias the single intervals up and the estimate down.
                let slot = c.normal_batches % 64;
                let t0 = (slot == 31 || slot == 63).then(std::time::Instant::now);
                let mut normals = [Vec3::Y; CAMERA_BATCH];
                mapped(&mut normals[..n]);
                if slot == 63 {
                    let mut again = [Vec3::Y; CAMERA_BATCH];
                    std::hint::black_box(&uv);
                    mapped(&mut again[..n]);
                    std::hint::black_box(&again);
                }
                if let Some(t0) = t0 {
                    let ns = t0.elapsed().as_nanos() as u64;
                    if slot == 31 {
                        c.normal_timed += 1;
                        c.normal_timed_ns += ns;
                        c.normal_timed_points += n as u64;
                    } else {
                        c.normal_timed_twice += 1;
                        c.normal_timed_twice_ns += ns;
                        c.normal_timed_twice_points += n as u64;
                    }
                }
                c.normal_batches += 1;
                c.normal_evals += n as u64;
                for (&i, nm) in at[..n].iter().zip(normals) {
                    out[i as usize] = nm;
                }
            }
            (NormalMode::Geometric, _) => {
                for (o, h) in out.iter_mut().zip(hits) {
                    if let Some(h) = h {
                        *o = match self.accel.surface_normal(h) {
                            Some((n, _)) => Vec3::from(n).normalize_or(Vec3::Y),
                            None => surface_point(mesh, h).ng,
                        };
                    }
                }
            }
            _ => {
                for (o, h) in out.iter_mut().zip(hits) {
                    *o = match h {
                        Some(h) if !mesh.normals().is_empty() => {
                            let tri = mesh.indices()[h.prim as usize];
                            Vec3::from(Mesh::interpolate(mesh.normals(), tri, h.u, h.v))
                                .normalize_or(Vec3::Y)
                        }
                        _ => Vec3::Y,
                    };
                }
            }
        }
    }
}
