//! `vastocean mesh`: the LOD doubling tessellation of a scene's `[lod]` section, counted or
//! built over the default ocean (and optionally exported as binary PLY).

use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

use super::AppError;
use crate::config::{CameraConfig, LodConfig, Pattern};
use crate::lod::{LodParams, LodStats};
use crate::ocean::{OceanParams, Surface};

/// A mesh job: the tessellation as a scene would ask for it, and what to do with it.
#[derive(Clone, Debug)]
pub struct MeshJob {
    pub lod: LodConfig,
    /// Camera height, and width for `auto`.
    pub camera: CameraConfig,
    pub pattern: Pattern,
    /// Seed of the ocean sampled at every vertex (the default ocean).
    pub seed: u64,
    /// Count the triangles without building the mesh.
    pub count_only: bool,
    pub ply: Option<PathBuf>,
}

#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    pub triangles: usize,
    pub vertices: usize,
    pub max_distance_m: f64,
    /// Present when the mesh was built (the stats' headline figures are repeated at the top).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rings: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stats: Option<LodStats>,
    pub params: LodParams,
    #[serde(skip)]
    pub preset: crate::config::LodChoice,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ply: Option<PathBuf>,
}

pub fn run(job: &MeshJob) -> Result<MeshReport, AppError> {
    job.lod.validate()?;
    job.camera.validate()?;
    if let Some(path) = &job.ply {
        super::check_outputs(std::slice::from_ref(path))?;
    }
    let mut params = crate::lod::params_for(&job.lod, &job.camera)?;
    params.pattern = job.pattern;
    params.validate()?;
    let report = |triangles, vertices, max_distance_m, stats: Option<LodStats>| MeshReport {
        triangles,
        vertices,
        max_distance_m,
        rings: stats.as_ref().map(|s| s.rings),
        bytes: stats.as_ref().map(|s| s.bytes),
        seconds: stats.as_ref().map(|s| s.seconds),
        stats,
        params: params.clone(),
        preset: job.lod.preset,
        ply: job.ply.clone(),
    };
    if job.count_only {
        let c = crate::lod::try_count(&params)?;
        return Ok(report(c.triangles, c.vertices, c.max_distance_m, None));
    }
    let ocean = Surface::new(&OceanParams::default(), job.seed)?;
    let (mesh, stats) = crate::lod::tessellate(&params, &ocean.sampler([0.0, 0.0]))?;
    if let Some(path) = &job.ply {
        crate::mesh::write_ply(&mesh, path)?;
    }
    Ok(report(
        stats.triangles,
        stats.vertices,
        stats.max_distance_m,
        Some(stats),
    ))
}

impl fmt::Display for MeshReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(stats) = &self.stats else {
            return write!(
                f,
                "{} triangles, {} vertices out to {:.0} m",
                self.triangles, self.vertices, self.max_distance_m
            );
        };
        writeln!(
            f,
            "LOD {}, reading {}, pattern {}: {} triangles, {} vertices, {} rings out to {:.0} m, {:.1} MB, {:.2} s",
            self.preset,
            self.params.reading,
            self.params.pattern,
            stats.triangles,
            stats.vertices,
            stats.rings,
            stats.max_distance_m,
            stats.bytes as f64 / 1e6,
            stats.seconds
        )?;
        write!(
            f,
            "  ring   triangle size (m)   from (m)     to (m)   triangles"
        )?;
        for (i, r) in stats.per_ring.iter().enumerate() {
            write!(
                f,
                "\n  {i:>4} {:>19.3} {:>10.1} {:>10.1} {:>11}",
                r.size_m, r.inner_m, r.outer_m, r.triangles
            )?;
        }
        if let Some(path) = &self.ply {
            write!(f, "\n  wrote {}", path.display())?;
        }
        Ok(())
    }
}
