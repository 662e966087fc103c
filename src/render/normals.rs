//! Shading normals at a batch of hits: the interpolated vertex normals, the ocean's own
//! normals recomputed from the layers at the interpolated texture coordinate (paper section 4),
//! with the cost of the mapped normals measured as the render goes, or the surface's own
//! geometric normal; for filtered normals, the normal of the waves the footprint resolves and
//! what it leaves unresolved.

use glam::Vec3;

use super::counters::Counters;
use super::earth_tilt::tilt_to_earth_many;
use super::footprint::mesh_sigma;
use super::integrator::{CAMERA_BATCH, SceneRef, TraceSettings};
use super::interface::surface_point;
use crate::accel::Hit;
use crate::config::NormalMode;
use crate::mesh::Mesh;
use crate::ocean::slopes::{ALL_WAVES, LevelSet, Split};

/// What filtered normals leave to the lobe at a hit: the unresolved waves' slope covariance
/// (xx, xz, zz) in the flat sea's axes, and the local vertical, from which those slopes (and
/// the resolved normal's) are measured.
#[derive(Clone, Copy, Debug)]
pub(super) struct Unresolved {
    pub(super) cov: [f32; 3],
    pub(super) up: Vec3,
}

impl Unresolved {
    /// Nothing unresolved (every mode but filtered normals, and a miss).
    pub(super) const NONE: Unresolved = Unresolved {
        cov: [0.0; 3],
        up: Vec3::Y,
    };
}

/// What each hit of a batch resolves, for filtered normals.
#[derive(Clone, Copy)]
pub(super) enum Footprints<'a> {
    /// The footprint's width at each hit, m (a mesh: the waves it resolves are read there).
    Widths(&'a [f32]),
    /// The surface of the layers' levels each hit lies on (the exact surface: the waves it
    /// holds are the resolved ones).
    Levels(&'a [LevelSet]),
}

impl SceneRef<'_> {
    /// The shading normals (air side up) at a batch of hits into `out` (a miss's entry is
    /// not used: left as it is, or +y).
    /// Mapped normals: each hit's texture coordinate, the ocean's normals there computed
    /// together ([`Sampler::normals`], bit for bit one at a time), tilted to the curved earth.
    /// Filtered normals: the same, each layer read from the low-passed levels that the hit's
    /// footprint resolves, and the slopes of the rest into `rough`
    /// ([`crate::ocean::slopes::SurfaceSlopes::split`]; left as it is for other modes); on
    /// the exact surface, the levels of the surface hit, and what they leave out
    /// ([`crate::ocean::slopes::SurfaceSlopes::split_of`]).
    /// One call in 64 is timed alone, one timed with a second evaluation of the same normals
    /// (see [`Counters::normal_map_thread_seconds`]).
    pub(super) fn shading_normals(
        &self,
        hits: &[Option<Hit>],
        footprints: Footprints,
        settings: &TraceSettings,
        c: &mut Counters,
        out: &mut [Vec3],
        rough: &mut [Unresolved],
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
                let mut splits = [Split::RESOLVED; CAMERA_BATCH];
                // (Without the slopes every wave counts as resolved: mapped normals.)
                let slopes = self.slopes.filter(|_| filtered);
                if let Some(slopes) = slopes {
                    let mut ups = [Vec3::Y; CAMERA_BATCH];
                    tilt_to_earth_many(&uv[..n], self.earth_radius_m, &mut ups[..n]);
                    for (j, &i) in at[..n].iter().enumerate() {
                        let i = i as usize;
                        let h = hits[i].expect("a hit's entry");
                        splits[j] = match footprints {
                            Footprints::Levels(lods) => slopes.split_of(&lods[i]),
                            Footprints::Widths(widths) => {
                                let tri =
                                    mesh.indices()[h.prim as usize].map(|v| mesh.uvs()[v as usize]);
                                slopes
                                    .split((widths[i] * settings.filter_width).min(mesh_sigma(tri)))
                            }
                        };
                        rough[i] = Unresolved {
                            cov: splits[j].cov,
                            up: ups[j],
                        };
                    }
                }
                let mapped = |normals: &mut [Vec3]| {
                    let mut flat = [[0.0f32; 3]; CAMERA_BATCH];
                    if slopes.is_some() {
                        ocean.normals_split(&uv[..n], &splits[..n], &mut flat[..n]);
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
                        *o = match self.accel.surface_normal(h, &ALL_WAVES) {
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
