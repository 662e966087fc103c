//! `mesh`: the tessellation's flags.

use std::path::PathBuf;

use vastocean::app;
use vastocean::config::{LodChoice, LodConfig};

use super::choice;

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct MeshArgs {
    /// Start from one of the paper's tessellations, or `auto` (flags below override it).
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
    lod: LodChoice,
    /// Triangle size next to the camera, m.
    #[arg(long)]
    near_size: Option<f64>,
    /// Double distance, m.
    #[arg(long)]
    double_distance: Option<f64>,
    /// Most doublings (generations).
    #[arg(long)]
    generations: Option<u32>,
    /// Where the tessellation ends, m (default: just past the horizon).
    #[arg(long)]
    max_distance: Option<f64>,
    /// Camera height above the sea, m.
    #[arg(long, default_value_t = 2.0)]
    camera_height: f64,
    /// Image width `auto` sizes the triangles for.
    #[arg(long, default_value_t = 2048)]
    width: usize,
    /// `square` (all directions) or `frustum:YAW_DEG:HFOV_DEG` (a perspective camera's view).
    #[arg(long, default_value = "square")]
    pattern: vastocean::config::Pattern,
    /// How the paper's doubling rule is read (docs/scene-file.md, `lod.reading`).
    #[arg(long, value_parser = choice::<vastocean::config::Reading>())]
    reading: Option<vastocean::config::Reading>,
    /// Seed of the ocean sampled at every vertex (the default case-22 ocean).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Count the triangles without building the mesh.
    #[arg(long)]
    count_only: bool,
    /// Write the mesh as binary PLY (positions, normals, texture coordinates).
    #[arg(long)]
    ply: Option<PathBuf>,
    /// Print the result as one JSON object on stdout instead of the report.
    #[arg(long)]
    pub json: bool,
}

impl MeshArgs {
    pub fn job(&self) -> app::mesh::MeshJob {
        app::mesh::MeshJob {
            lod: LodConfig {
                preset: self.lod,
                near_size_m: self.near_size,
                double_distance_m: self.double_distance,
                generations: self.generations,
                max_distance_m: self.max_distance,
                reading: self.reading,
            },
            camera: vastocean::config::CameraConfig {
                height_m: self.camera_height,
                width: self.width,
                ..Default::default()
            },
            pattern: self.pattern,
            seed: self.seed,
            count_only: self.count_only,
            ply: self.ply.clone(),
        }
    }
}
