//! `vastocean crosscheck`: the same rays (random ones over the mesh and a small panorama's
//! camera rays) through Embree and the Rust BVH, compared hit for hit, and the same small
//! render through each backend, compared pixel by pixel.

use std::fmt;
use std::sync::Arc;

use serde::Serialize;

use super::AppError;
use crate::accel::Ray;
use crate::accel::crosscheck::{CrossReport, crosscheck, crosscheck_exact, random_rays_over};
use crate::accel::exact::ExactSurface;
use crate::color::luminance;
use crate::config::{Backend, LodChoice, Projection, SceneConfig, SurfaceKind};
use crate::image_io::RgbImage;
use crate::ocean::Surface;
use crate::render::Camera;
use crate::render::pipeline::render_scene;

#[derive(Clone, Debug)]
pub struct CrosscheckJob {
    /// The ocean mesh to trace (the default ocean, camera 2 m up).
    pub lod: LodChoice,
    /// Random rays aimed into the mesh's bounds.
    pub rays: usize,
    /// Width and samples per pixel of the small 360-degree render.
    pub width: usize,
    pub spp: u32,
    pub seed: u64,
    pub threads: usize,
    /// The mesh's triangles, or the exact displaced surface inside them.
    pub surface: SurfaceKind,
}

/// How two images of one scene differ.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ImageDifference {
    pub pixels: usize,
    /// Pixels whose RGB bits differ.
    pub differing: usize,
    pub max_luminance_difference: f32,
    pub mean_abs_luminance_difference: f64,
    pub mean_luminance: f64,
}

impl ImageDifference {
    pub fn of(a: &RgbImage, b: &RgbImage) -> ImageDifference {
        let pairs = || a.pixels.iter().zip(&b.pixels);
        let n = a.pixels.len();
        ImageDifference {
            pixels: n,
            differing: pairs()
                .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
                .count(),
            max_luminance_difference: pairs()
                .map(|(p, q)| (luminance(*p) - luminance(*q)).abs())
                .fold(0f32, f32::max),
            mean_abs_luminance_difference: pairs()
                .map(|(p, q)| (luminance(*p) - luminance(*q)).abs() as f64)
                .sum::<f64>()
                / n as f64,
            mean_luminance: a.pixels.iter().map(|p| luminance(*p) as f64).sum::<f64>() / n as f64,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct CrosscheckReport {
    #[serde(flatten)]
    pub rays: CrossReport,
    pub camera_rays: usize,
    #[serde(skip)]
    pub lod: LodChoice,
    pub surface: SurfaceKind,
    #[serde(skip)]
    pub render_size: (usize, usize, u32),
    pub render_pixels: usize,
    pub render_differing_fraction: f64,
    pub render_max_luminance_difference: f32,
    pub render_mean_luminance: f64,
    pub render_mean_abs_luminance_difference: f64,
}

/// Runs the cross-check. Unexplained disagreements are not an error here: the caller decides
/// (the command exits 1 on any).
pub fn run(job: &CrosscheckJob) -> Result<CrosscheckReport, AppError> {
    let mut cfg = SceneConfig::default();
    cfg.lod.preset = job.lod;
    cfg.camera.width = job.width;
    cfg.render.spp = job.spp;
    cfg.render.seed = job.seed;
    cfg.render.threads = job.threads;
    cfg.render.surface = job.surface;
    cfg.validate()?;
    let lod = crate::lod::params_for(&cfg.lod, &cfg.camera)?;
    let ocean = Arc::new(Surface::new(&cfg.ocean, cfg.render.ocean_seed)?);
    let (mesh, _) = crate::lod::tessellate(&lod, &ocean.sampler(cfg.camera.position_m))?;
    let mut rays = random_rays_over(&mesh, job.rays, job.seed);
    let camera = Camera::new(Projection::Equirect { band_deg: None }, job.width, 2.0);
    let eye = [0.0, cfg.camera.height_m as f32, 0.0];
    for y in 0..camera.height {
        for x in 0..camera.width {
            let d = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
            rays.push(Ray::new(eye, d.to_array()));
        }
    }
    let report = match job.surface {
        SurfaceKind::Mesh => crosscheck(Arc::new(mesh), &rays, job.threads)?,
        SurfaceKind::Exact => {
            let surface = || {
                ExactSurface::new(
                    ocean.clone(),
                    cfg.camera.position_m,
                    lod.earth_radius_m,
                    false,
                )
                .expect("a scene that validated has bilinear reads")
            };
            crosscheck_exact(Arc::new(mesh), surface, &rays, job.threads)?
        }
    };

    // The same small render through each backend, same seed: which pixels differ, and by how much.
    let mut images = Vec::new();
    for backend in [Backend::Embree, Backend::Rust] {
        let mut c = cfg.clone();
        c.render.backend = backend;
        images.push(render_scene(&c, false)?.film.image);
    }
    let d = ImageDifference::of(&images[0], &images[1]);
    Ok(CrosscheckReport {
        rays: report,
        camera_rays: camera.width * camera.height,
        lod: job.lod,
        surface: job.surface,
        render_size: (camera.width, camera.height, job.spp),
        render_pixels: d.pixels,
        render_differing_fraction: d.differing as f64 / d.pixels as f64,
        render_max_luminance_difference: d.max_luminance_difference,
        render_mean_luminance: d.mean_luminance,
        render_mean_abs_luminance_difference: d.mean_abs_luminance_difference,
    })
}

impl fmt::Display for CrosscheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.rays;
        writeln!(
            f,
            "crosscheck on {}, surface {} ({} rays, {} of them camera rays):",
            self.lod, self.surface, r.rays, self.camera_rays
        )?;
        writeln!(
            f,
            "  agree {:.6} (same {} {}, both miss {}), disagreements {}: {} explained (edge/vertex or tie; {} of them by rounding at the ray's distance alone), {} unexplained",
            r.agree_fraction,
            match self.surface {
                SurfaceKind::Mesh => "triangle",
                SurfaceKind::Exact => "crossing",
            },
            r.same_prim,
            r.both_miss,
            r.disagreements,
            r.explained_disagreements,
            r.explained_by_rounding_only,
            r.unexplained_disagreements
        )?;
        writeln!(
            f,
            "  max relative t difference on agreeing hits{} {:.2e}",
            match self.surface {
                SurfaceKind::Mesh => ", times |cos incidence|",
                SurfaceKind::Exact => "",
            },
            r.max_rel_dt
        )?;
        writeln!(
            f,
            "  build: Embree {:.3} s, Rust {:.3} s; trace: Embree {:.2} Mrays/s, Rust {:.2} Mrays/s",
            r.embree_build_s, r.rust_build_s, r.embree_mrays_per_s, r.rust_mrays_per_s
        )?;
        let (w, h, spp) = self.render_size;
        writeln!(
            f,
            "  render {w} x {h} at {spp} spp with each backend: {:.4}% of {} pixels differ, mean absolute luminance difference {:.3e}, largest {:.3e} (mean luminance {:.3e})",
            100.0 * self.render_differing_fraction,
            self.render_pixels,
            self.render_mean_abs_luminance_difference,
            self.render_max_luminance_difference,
            self.render_mean_luminance
        )?;
        write!(
            f,
            "  (rays that agree up to rounding can still flip a Fresnel-weighted random branch or graze a sun glint, so single pixels of a few-sample render may differ a lot)"
        )
    }
}
