//! LOD tessellation of the ocean by the paper's *doubling method* (section 2 and Figure 1):
//! triangles of size `s` out to the double distance `d`, beyond which the triangle size and the
//! double distance both double, and so on, optionally for a capped number of generations, out to
//! just past the horizon of a curved earth. Both patterns of Figure 1 are built: nested square
//! grids in all directions ([`Pattern::Square`], for the 360-degree camera) and the part of them
//! a perspective camera can see ([`Pattern::Frustum`]). Every vertex holds the displaced,
//! camera-relative surface point X of eq. 4, the normal of eq. 7, both tilted into the
//! curved-earth frame, and its nominal horizontal position as texture coordinate (section 4).
//!
//! # Readings of the rule
//!
//! The text leaves three things open: where each ring ends (the worked example "beyond 14 m ...
//! double distance 28 m ... beyond 42 m" makes ring k `d 2^k` wide; "the range at which the size
//! of the triangles and the double-distance are both doubled" makes ring k end at `d 2^k`),
//! whether "6 generations of doubling" ends the tessellation or only the doubling, and whether
//! the ring that reaches the horizon is cut there or kept whole. [`Reading`] implements five
//! combinations. Ring edges are snapped to whole cells of the coarser ring, and the coarse
//! cells along each ring's hole are fanned to the finer ring's midpoint vertices (no T-junction;
//! see `build.rs`). The counts below come from the real tessellation ([`count_triangles`], equal
//! to what [`tessellate`] builds) for the paper's camera 2 m above the sea, square pattern, cut
//! at 5 300 m (the geometric horizon, 5 048 m, plus [`HORIZON_MARGIN`]), with the text's cap of
//! 6 generations and without a cap:
//!
//! | reading                | high, cap 6 | low, cap 6 | high, no cap | low, no cap |
//! |------------------------|-------------|------------|--------------|-------------|
//! | paper, section 5       |             |            |   22 341 600 |      25 520 |
//! | `nested-whole` (dflt)  |  15 854 400 |     18 080 |   22 341 600 |      25 520 |
//! | `nested`               |  15 854 400 |     18 080 |   20 047 904 |      23 064 |
//! | `widths`               |  49 098 392 |     56 112 |   57 203 344 |      65 608 |
//! | `nested-to-horizon`    |  60 884 136 |     68 816 |   as `nested` |  as `nested` |
//! | `widths-to-horizon`    |  85 660 280 |     97 248 |   as `widths` |  as `widths` |
//!
//! `nested-whole` without a cap reproduces both of the paper's counts exactly: with N = d / s
//! (600 and 20) they are 62 N^2 + 36 N, i.e. a central square of (2N)^2 cells and nine doubled
//! rings of 3 N^2 cells (ring k from d 2^(k-1) to d 2^k, the last, 4 608 to 9 216 m, holding the
//! 5 km horizon and kept whole), two triangles per cell plus one for each of the 4 N coarse
//! cells along every ring's hole. It is the default reading, and the [`Preset`]s have no cap.
//! The paper's text says "6 generations" with 1.9 m (58 m) triangles near the horizon; no
//! reading with 6 generations comes within 29 % of its counts, and its triangles at the horizon
//! are s 2^9: 15.4 m (high) and 461 m (low). Set `generations = Some(6)` for the text's version.

mod build;
mod earth;
mod grid;

use std::fmt;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::config::{CameraConfig, LodChoice, LodConfig, Projection};
use crate::mesh::{Mesh, MeshError};
use crate::ocean::{Sample, Sampler};

pub use crate::config::lod::{Pattern, Reading};

pub(crate) use earth::atan_over_arg;
use earth::curved_frame_point_near;
pub use earth::{curved_frame_point, curved_frame_position, horizon_distance};

/// Default earth radius, m (mean radius).
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// How far past the geometric horizon the tessellation goes by default, as a fraction of the
/// horizon distance H. A crest at distance (1 + f) H stays hidden unless it stands higher than
/// (f H)^2 / 2R: 5 mm for a 2 m camera, 25 cm for 100 m. Going further multiplies triangles
/// (the outermost ring holds most of them) for waves that rarely peek over the horizon.
pub const HORIZON_MARGIN: f64 = 0.05;

/// Angular margin of [`Pattern::Frustum`] on each side of the field of view, degrees: the
/// horizontal displacement D moves geometry sideways, and a cell just outside the wedge can
/// still throw a triangle into it.
pub const FRUSTUM_MARGIN_DEG: f64 = 3.0;

/// Most triangles [`tessellate`] will build (about 13 GB of buffers); beyond that the parameters
/// are almost certainly a mistake (e.g. millimetre triangles to the horizon).
pub const MAX_TRIANGLES: usize = 500_000_000;

/// How each reading treats the rings (see the module doc).
impl Reading {
    pub(crate) fn widths(self) -> bool {
        matches!(self, Reading::Widths | Reading::WidthsToHorizon)
    }
    pub(crate) fn cap_ends_tessellation(self) -> bool {
        matches!(
            self,
            Reading::NestedWhole | Reading::Nested | Reading::Widths
        )
    }
    pub(crate) fn whole_last_ring(self) -> bool {
        self == Reading::NestedWhole
    }
}

/// The two tessellations of the paper's section 5, as their triangle counts define them: no
/// generation cap, so with the default reading they have exactly the paper's 22 341 600 and
/// 25 520 triangles for a 2 m camera (see the module doc on the text's "6 generations").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// 3 cm near the camera, double distance 18 m.
    PaperHigh,
    /// 90 cm near the camera, double distance 18 m.
    PaperLow,
}

impl Preset {
    pub fn params(self, camera_height_m: f64) -> LodParams {
        let near_size_m = match self {
            Preset::PaperHigh => 0.03,
            Preset::PaperLow => 0.9,
        };
        LodParams {
            near_size_m,
            double_distance_m: 18.0,
            generations: None,
            max_distance_m: None,
            pattern: Pattern::Square,
            reading: Reading::default(),
            earth_radius_m: EARTH_RADIUS_M,
            camera_height_m,
        }
    }
}

/// Parameters of the doubling tessellation. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LodParams {
    /// Triangle (square cell) size next to the camera, s.
    pub near_size_m: f64,
    /// Double distance d: where the first doubling happens.
    pub double_distance_m: f64,
    /// Most doublings; `None` = double until the maximum distance.
    pub generations: Option<u32>,
    /// Horizontal (arc) distance the tessellation must reach; `None` = [`HORIZON_MARGIN`] past
    /// the horizon of a camera at `camera_height_m`. Cells beyond it are cut, except by
    /// [`Reading::NestedWhole`], which completes the ring that reaches it.
    pub max_distance_m: Option<f64>,
    pub pattern: Pattern,
    pub reading: Reading,
    pub earth_radius_m: f64,
    /// Camera height above mean sea level at its nadir.
    pub camera_height_m: f64,
}

#[derive(Debug, Error)]
pub enum LodError {
    #[error("{field} must be {requirement} (got {got})")]
    Invalid {
        field: String,
        requirement: String,
        got: String,
    },
    #[error(
        "lod would make {triangles} triangles, more than {limit}; raise lod.near_size_m or \
         lod.double_distance_m, or lower lod.max_distance_m"
    )]
    TooLarge { triangles: usize, limit: usize },
    #[error("lod.max_distance_m ({0} m) leaves no cell to tessellate")]
    Empty(f64),
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

fn invalid(field: &str, requirement: &str, got: impl fmt::Display) -> LodError {
    LodError::Invalid {
        field: format!("lod.{field}"),
        requirement: requirement.into(),
        got: got.to_string(),
    }
}

fn positive(field: &str, v: f64) -> Result<(), LodError> {
    // NaN is not finite.
    if !v.is_finite() || v <= 0.0 {
        return Err(invalid(field, "finite and > 0", v));
    }
    Ok(())
}

impl LodParams {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), LodError> {
        positive("near_size_m", self.near_size_m)?;
        positive("double_distance_m", self.double_distance_m)?;
        if self.double_distance_m < self.near_size_m {
            return Err(invalid(
                "double_distance_m",
                "at least lod.near_size_m",
                self.double_distance_m,
            ));
        }
        if let Some(g) = self.generations
            && g > 40
        {
            return Err(invalid("generations", "at most 40", g));
        }
        if let Some(m) = self.max_distance_m {
            positive("max_distance_m", m)?;
        }
        positive("earth_radius_m", self.earth_radius_m)?;
        positive("camera_height_m", self.camera_height_m)?;
        if self.camera_height_m >= self.earth_radius_m {
            return Err(invalid(
                "camera_height_m",
                "below lod.earth_radius_m",
                self.camera_height_m,
            ));
        }
        if let Pattern::Frustum { yaw_deg, hfov_deg } = self.pattern {
            if !yaw_deg.is_finite() {
                return Err(invalid("pattern.yaw_deg", "finite", yaw_deg));
            }
            if !(hfov_deg.is_finite() && hfov_deg > 0.0 && hfov_deg < 180.0) {
                return Err(invalid(
                    "pattern.hfov_deg",
                    "in (0, 180) for a perspective camera",
                    hfov_deg,
                ));
            }
        }
        Ok(())
    }

    /// Where the tessellation ends: `max_distance_m`, or just past the horizon.
    pub fn max_distance(&self) -> f64 {
        self.max_distance_m.unwrap_or_else(|| {
            horizon_distance(self.camera_height_m, self.earth_radius_m) * (1.0 + HORIZON_MARGIN)
        })
    }

    /// Sizes from the pixel footprint of an equirectangular camera `image_width_px` wide (angular
    /// pixel size a = 2 pi / W): near-camera triangles as wide as a pixel straight down
    /// (s = a h) and d = s / a = h, so in ring k (distance d 2^(k-1) to d 2^k, `nested`) the
    /// triangle size s 2^k stays between 0.58 and 2 times the pixel's cross-range footprint
    /// a sqrt(r^2 + h^2). Cross-range is the footprint's longer side at grazing angles, so no
    /// triangle is much smaller than a pixel in both directions. No generation cap.
    pub fn auto(camera_height_m: f64, image_width_px: u32) -> LodParams {
        let a = std::f64::consts::TAU / image_width_px.max(1) as f64;
        LodParams {
            near_size_m: a * camera_height_m,
            double_distance_m: camera_height_m,
            generations: None,
            max_distance_m: None,
            pattern: Pattern::Square,
            reading: Reading::Nested,
            earth_radius_m: EARTH_RADIUS_M,
            camera_height_m,
        }
    }
}

/// The parameters a scene's `[lod]` section asks for, for its camera: the preset (or `auto`
/// from the image width) with the section's overrides applied. The pattern follows the camera:
/// all directions for the 360 degree camera, only the field of view for a pinhole (skip what is
/// not seen).
pub fn params_for(lod: &LodConfig, camera: &CameraConfig) -> Result<LodParams, LodError> {
    let h = camera.height_m;
    let mut p = match lod.preset {
        LodChoice::PaperHigh => Preset::PaperHigh.params(h),
        LodChoice::PaperLow | LodChoice::Custom => Preset::PaperLow.params(h),
        LodChoice::Auto => LodParams::auto(h, camera.width as u32),
    };
    if lod.preset == LodChoice::Custom
        && (lod.near_size_m.is_none() || lod.double_distance_m.is_none())
    {
        return Err(invalid(
            "near_size_m and lod.double_distance_m",
            "set when lod.preset = \"custom\"",
            "nothing",
        ));
    }
    if let Some(v) = lod.near_size_m {
        p.near_size_m = v;
    }
    if let Some(v) = lod.double_distance_m {
        p.double_distance_m = v;
    }
    if lod.generations.is_some() {
        p.generations = lod.generations;
    }
    if lod.max_distance_m.is_some() {
        p.max_distance_m = lod.max_distance_m;
    }
    if let Some(r) = lod.reading {
        p.reading = r;
    }
    // A pinhole keeps the cells under the azimuths where its image sees the sea (a camera
    // looking down sees much further sideways at its corners than its horizontal field of view).
    if matches!(camera.projection, Projection::Pinhole { .. }) {
        p.pattern = match camera.sea_azimuths_deg() {
            Some((yaw_deg, half)) => Pattern::Frustum {
                yaw_deg,
                hfov_deg: (2.0 * half).max(1.0),
            },
            None => Pattern::Square,
        };
    }
    p.validate()?;
    Ok(p)
}

/// One ring of the tessellation in the statistics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RingStats {
    /// Triangle (cell) size.
    pub size_m: f64,
    /// Half-width of the square hole (0 for the innermost ring).
    pub inner_m: f64,
    /// Half-width of the outer square (cells beyond the maximum distance are cut).
    pub outer_m: f64,
    pub triangles: usize,
}

/// What [`tessellate`] built.
#[derive(Clone, Debug, Serialize)]
pub struct LodStats {
    pub triangles: usize,
    pub vertices: usize,
    pub rings: usize,
    /// Where the tessellation was cut, or for [`Reading::NestedWhole`] the half-width of its
    /// outer square.
    pub max_distance_m: f64,
    pub seconds: f64,
    /// Bytes of the mesh buffers.
    pub bytes: usize,
    pub per_ring: Vec<RingStats>,
}

/// Builds the mesh, sampling the ocean at every vertex (in parallel, by rows).
pub fn tessellate(params: &LodParams, sampler: &Sampler) -> Result<(Mesh, LodStats), LodError> {
    let start = std::time::Instant::now();
    params.validate()?;
    let geo = grid::Geometry::new(params)?;
    let (mesh, per_ring) = geo.build(params, sampler)?;
    let stats = LodStats {
        triangles: mesh.triangle_count(),
        vertices: mesh.vertex_count(),
        rings: per_ring.len(),
        max_distance_m: geo.max_distance(),
        seconds: start.elapsed().as_secs_f64(),
        bytes: mesh.bytes(),
        per_ring,
    };
    Ok((mesh, stats))
}

/// The displaced position and normal of every vertex from its nominal position (texture
/// coordinate) `uvs`, as [`tessellate`] computes them: for an animation frame, whose topology
/// is the first frame's and whose surface has moved on in time. Bit-identical to a fresh
/// tessellation of the same surface.
pub fn displace(
    uvs: &[[f32; 2]],
    sampler: &Sampler,
    earth_radius_m: f64,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    use rayon::prelude::*;
    let mut positions = vec![[0.0f32; 3]; uvs.len()];
    let mut normals = vec![[0.0f32; 3]; uvs.len()];
    const CHUNK: usize = 4096;
    uvs.par_chunks(CHUNK)
        .zip(positions.par_chunks_mut(CHUNK))
        .zip(normals.par_chunks_mut(CHUNK))
        .for_each(|((uv, pos), nrm)| displace_into(uv, sampler, earth_radius_m, pos, nrm));
    (positions, normals)
}

/// The displaced position and normal at each nominal position `uvs[i]` into `positions[i]` and
/// `normals[i]`: the layers read for 64 points at a time ([`Sampler::samples`]), bit for bit
/// one by one.
pub(crate) fn displace_into(
    uvs: &[[f32; 2]],
    sampler: &Sampler,
    earth_radius_m: f64,
    positions: &mut [[f32; 3]],
    normals: &mut [[f32; 3]],
) {
    let mut samples = [Sample::FLAT; 64];
    for ((uv, pos), nrm) in uvs
        .chunks(64)
        .zip(positions.chunks_mut(64))
        .zip(normals.chunks_mut(64))
    {
        let samples = &mut samples[..uv.len()];
        sampler.samples(uv, samples);
        // the series for every vertex (vector code), then libm's functions for any past its
        // reach, which a sea's vertices never are on the earth
        let mut far = false;
        for (((&[u, w], s), p), n) in uv.iter().zip(&*samples).zip(&mut *pos).zip(&mut *nrm) {
            let (pp, nn, near) = curved_frame_point_near(u as f64, w as f64, s, earth_radius_m);
            *p = pp.map(|c| c as f32);
            *n = nn.map(|c| c as f32);
            far |= !near;
        }
        if far {
            for (((&[u, w], s), p), n) in uv.iter().zip(&*samples).zip(pos).zip(nrm) {
                let (pp, nn) = curved_frame_point(u as f64, w as f64, s, earth_radius_m);
                *p = pp.map(|c| c as f32);
                *n = nn.map(|c| c as f32);
            }
        }
    }
}

/// The exact number of triangles [`tessellate`] would build, without building anything.
/// Panics if `params` is invalid (see [`LodParams::validate`]).
pub fn count_triangles(params: &LodParams) -> usize {
    try_count(params).expect("valid LodParams").triangles
}

/// What [`tessellate`] would build, counted without building it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshCount {
    pub triangles: usize,
    pub vertices: usize,
    /// As [`LodStats::max_distance_m`].
    pub max_distance_m: f64,
}

/// Triangles, vertices and extent [`tessellate`] would build.
pub fn try_count(params: &LodParams) -> Result<MeshCount, LodError> {
    params.validate()?;
    let geo = grid::Geometry::new(params)?;
    let (triangles, vertices) = geo.count();
    Ok(MeshCount {
        triangles,
        vertices,
        max_distance_m: geo.max_distance(),
    })
}

/// The rings for `params`: (size, inner half-width, outer half-width), metres.
pub fn rings(params: &LodParams) -> Result<Vec<(f64, f64, f64)>, LodError> {
    params.validate()?;
    let geo = grid::Geometry::new(params)?;
    Ok(geo.ring_extents())
}
