//! One render job, end to end: ocean layers -> LOD tessellation -> Embree BVH -> path tracing
//! -> EXR + PNG preview + JSON sidecar. Each phase is timed; the sidecar records everything
//! needed to reproduce and judge the image (configuration, seed, triangle counts, timings, ray
//! counts, the NaN guard and wrong-side counts).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use super::film::{PixelState, Samples};
use super::integrator::{highest_vertex_y, max_slope};
pub use super::limits::{MAX_FOLDED_FRACTION, RenderError, bytes_per_triangle};
use super::limits::{OceanAtHand, check_memory};
pub use super::report::{PassInfo, RenderReport, Rendered, mean_luminance, warnings};
use super::{Camera, SceneRef, TraceSettings, render_image_samples};
use crate::accel::bvh::Bvh;
#[cfg(feature = "embree")]
use crate::accel::embree::{BuildOptions, Device, ExactScene, Scene};
use crate::accel::exact::{Exact, ExactSurface};
use crate::accel::{Accel, tracing_pool};
use crate::config::{Backend, SceneConfig, SurfaceKind};
use crate::lod::{EARTH_RADIUS_M, LodParams, LodStats, tessellate};
use crate::objects::SceneObjects;
use crate::ocean::Surface;
use crate::sky::Sky;

/// The height of the sea surface right under the camera, m (see
/// [`crate::objects::surface_height_at`]).
pub fn surface_height_at_nadir(sampler: &crate::ocean::Sampler) -> f64 {
    crate::objects::surface_height_at(sampler, 0.0, 0.0)
}

/// Builds the sky a scene asks for.
pub fn make_sky(cfg: &SceneConfig) -> Result<Sky, RenderError> {
    let mut sky = match &cfg.sky.file {
        Some(f) => Sky::load(f)?,
        None => Sky::analytic(cfg.sky.analytic),
    };
    if let Some(c) = cfg.sky.clip_relative {
        sky.clip_relative(c);
    }
    sky.dome_altitude_m = cfg.sky.dome_altitude_m;
    sky.earth_radius_m = EARTH_RADIUS_M;
    sky.camera_height_m = cfg.camera.height_m;
    sky.scale = cfg.sky.scale;
    Ok(sky)
}

/// Everything a render needs that does not depend on the camera's samples: the ocean, its
/// tessellation, the BVH and the sky, built once and traced as often as wanted (the scenario
/// comparison traces one mesh with both normal modes and two seeds).
pub struct Prepared {
    /// Shared with another prepared scene when [`Setup::ocean`] handed it in.
    pub ocean: Arc<Surface>,
    pub lod: LodParams,
    /// The BVH the scene asked for (`render.backend`).
    pub accel: Box<dyn Accel>,
    pub seconds_build: f64,
    /// Embree's version when the Embree backend traces.
    pub embree_version: Option<String>,
    /// Shared with another prepared scene when [`Setup::sky`] handed it in.
    pub sky: Arc<Sky>,
    pub skip_slope: Option<f32>,
    pub skip_above_y: Option<f32>,
    /// The sky's downwelling irradiance, which sets the water-leaving radiance.
    pub sky_irradiance: glam::Vec3,
    pub stats: LodStats,
    pub seconds_ocean: f64,
    pub seconds_tessellation: f64,
    pub threads: usize,
    pool: rayon::ThreadPool,
    camera_position_m: [f64; 2],
    /// The objects on the sea, placed at the ocean's time, and what placed them.
    pub objects: Option<SceneObjects>,
    object_configs: Vec<crate::config::ObjectConfig>,
    backend: Backend,
    /// The camera as its mount placed it (`camera.mount`), which renders use in place of the
    /// scene's.
    pub mounted: Option<crate::config::CameraConfig>,
}

/// How [`prepare_with`] builds a scene.
#[derive(Clone, Default)]
pub struct Setup {
    /// Embree builds a BVH it can refit ([`Prepared::advance_to`] moves the scene to another
    /// time), as an animation needs.
    pub refittable: bool,
    /// A spinner on stderr for each phase (the ocean's FFTs, the tessellation, the BVH build).
    pub progress: bool,
    /// An ocean already built for this scene's `[ocean]` and `render.ocean_seed`, used instead
    /// of building it again (the comparison's tessellations share one, as do the accuracy
    /// benchmark's); one built for
    /// another sea or seed is refused. Such a scene cannot [`Prepared::advance_to`].
    pub ocean: Option<Arc<Surface>>,
    /// A sky already built for this scene's `[sky]` and camera height, used instead of loading
    /// it again (the comparison's tessellations share one, as do the accuracy benchmark's).
    pub sky: Option<Arc<Sky>>,
}

/// Builds the ocean, the tessellation and the BVH of a validated scene.
pub fn prepare(cfg: &SceneConfig) -> Result<Prepared, RenderError> {
    prepare_with(cfg, Setup::default())
}

/// As [`prepare`], for an animation (see [`Setup::refittable`]).
pub fn prepare_for_frames(cfg: &SceneConfig) -> Result<Prepared, RenderError> {
    prepare_with(
        cfg,
        Setup {
            refittable: true,
            ..Setup::default()
        },
    )
}

/// A spinner on stderr naming a set-up phase that can take seconds (two 2048-texel layers,
/// paper-high's 22 M-triangle BVH), cleared when the phase ends. Hidden without `progress`;
/// indicatif draws nothing when stderr is not a terminal.
fn phase(progress: bool, message: String) -> indicatif::ProgressBar {
    if !progress {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner().with_message(message);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg}  {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    bar
}

/// The ocean of `cfg` (on the calling thread pool) and the seconds it took.
fn build_ocean(cfg: &SceneConfig, progress: bool) -> Result<(Arc<Surface>, f64), RenderError> {
    let t = Instant::now();
    let bar = phase(
        progress,
        format!("ocean: {} FFT layers", cfg.ocean.layers.len()),
    );
    let ocean = Surface::new(&cfg.ocean, cfg.render.ocean_seed)?;
    // where the fold bound does not clear the sea, its sampled estimate is part of the build's
    // time (it is kept, so the check after the build reads it)
    ocean.folded_fraction();
    bar.finish_and_clear();
    Ok((Arc::new(ocean), t.elapsed().as_secs_f64()))
}

/// Builds the ocean, the tessellation and the BVH of a validated scene, as `setup` says. A
/// camera an object carries (`camera.mount`) is placed once the ocean is built, and the scene
/// is prepared around its place.
pub fn prepare_with(cfg: &SceneConfig, setup: Setup) -> Result<Prepared, RenderError> {
    if cfg.camera.mount.is_some() {
        return prepare_mounted(cfg, setup);
    }
    let Setup {
        refittable,
        progress,
        ocean: shared_ocean,
        sky: shared_sky,
    } = setup;
    if let Some(o) = &shared_ocean
        && (o.params() != &cfg.ocean || o.seed() != cfg.render.ocean_seed)
    {
        return Err(RenderError::SharedOcean(
            "was built for another sea state or seed than this scene's",
        ));
    }
    // (the Rust BVH refits whatever it was built for; only Embree needs telling)
    #[cfg(not(feature = "embree"))]
    let _ = refittable;
    cfg.validate()?;
    let lod = crate::lod::params_for(&cfg.lod, &cfg.camera)?;
    check_memory(
        cfg,
        crate::lod::try_count(&lod)?.triangles,
        super::film::MAX_BATCHES,
        false,
        match &shared_ocean {
            Some(o) => OceanAtHand::Shared {
                levels: o.levels_built(),
            },
            None => OceanAtHand::None,
        },
    )?;
    let pool = tracing_pool(cfg.render.threads)?;
    let threads = pool.current_num_threads();
    // A sky map is read on a thread of its own while the ocean is built: its read is serial
    // (20 ms for a 2048 x 1024 map), and the ocean's transforms leave gaps on a core. One that
    // cannot be opened is said at once, not after the ocean's build.
    if let (None, Some(path)) = (&shared_sky, &cfg.sky.file) {
        std::fs::File::open(path).map_err(|e| crate::image_io::ImageError::Read {
            path: path.clone(),
            message: e.to_string(),
        })?;
    }
    let (sky, built) = std::thread::scope(|s| {
        let sky = s.spawn(|| match shared_sky {
            Some(sky) => Ok(sky),
            None => make_sky(cfg).map(Arc::new),
        });
        let built = pool.install(|| -> Result<_, RenderError> {
            let (ocean, seconds_ocean) = match shared_ocean {
                Some(ocean) => (ocean, 0.0),
                None => build_ocean(cfg, progress)?,
            };
            let folded = ocean.folded_fraction();
            if folded > MAX_FOLDED_FRACTION {
                return Err(RenderError::Folded {
                    folded,
                    choppiness: cfg.ocean.choppiness,
                });
            }
            let surface_m = surface_height_at_nadir(&ocean.sampler(cfg.camera.position_m));
            if cfg.camera.height_m <= surface_m {
                return Err(RenderError::CameraUnderwater {
                    camera_m: cfg.camera.height_m,
                    surface_m,
                });
            }
            let t = Instant::now();
            let bar = phase(progress, "tessellation".into());
            let (mesh, stats) = tessellate(&lod, &ocean.sampler(cfg.camera.position_m))?;
            bar.finish_and_clear();
            Ok((ocean, seconds_ocean, mesh, stats, t.elapsed().as_secs_f64()))
        });
        let sky = sky.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
        (sky, built)
    });
    let sky = sky?;
    let (ocean, seconds_ocean, mesh, stats, mut seconds_tessellation) = built?;
    let exact = cfg.render.surface == SurfaceKind::Exact;
    // (the exact surface's bounds are its prisms', set below; the mesh's count as its
    // tessellation's time)
    let t = Instant::now();
    let (skip_slope, mut skip_above_y) = if exact {
        (None, None)
    } else {
        pool.install(|| (max_slope(&mesh), highest_vertex_y(&mesh)))
    };
    seconds_tessellation += t.elapsed().as_secs_f64();
    let mesh = Arc::new(mesh);
    let bar = phase(
        progress,
        format!(
            "BVH over {} triangles ({})",
            mesh.triangle_count(),
            cfg.render.backend
        ),
    );
    let (accel, seconds_build, embree_version): (Box<dyn Accel>, f64, Option<String>) =
        match cfg.render.backend {
            _ if exact => {
                // the pyramids are part of the build (on the scene's threads)
                let t = Instant::now();
                let surface = pool
                    .install(|| {
                        ExactSurface::new(
                            ocean.clone(),
                            cfg.camera.position_m,
                            lod.earth_radius_m,
                            cfg.render.normals == crate::config::NormalMode::Filtered,
                        )
                    })
                    .map_err(RenderError::Exact)?;
                let pyramids_s = t.elapsed().as_secs_f64();
                match cfg.render.backend {
                    Backend::Rust => {
                        let exact = pool.install(|| Exact::build(mesh, surface));
                        skip_above_y = Some(exact.top_y());
                        let s = pyramids_s + exact.build_seconds();
                        (Box::new(exact), s, None)
                    }
                    #[cfg(not(feature = "embree"))]
                    Backend::Embree => return Err(RenderError::NoEmbree),
                    #[cfg(feature = "embree")]
                    Backend::Embree => {
                        let device = Device::new(threads)?;
                        let exact = pool.install(|| {
                            ExactScene::new(&device, mesh, surface, BuildOptions::default())
                        })?;
                        skip_above_y = Some(exact.top_y());
                        let s = pyramids_s + exact.build_seconds();
                        (Box::new(exact), s, Some(device.version()))
                    }
                }
            }
            #[cfg(not(feature = "embree"))]
            Backend::Embree => return Err(RenderError::NoEmbree),
            #[cfg(feature = "embree")]
            Backend::Embree => {
                let device = Device::new(threads)?;
                let options = BuildOptions {
                    quality: if refittable {
                        crate::accel::embree::Quality::Refit
                    } else {
                        BuildOptions::default().quality
                    },
                    compact: cfg.render.compact_bvh,
                    grids: super::limits::embree_grids(cfg, mesh.triangle_count()),
                    ..BuildOptions::default()
                };
                let scene = Scene::new(&device, mesh, options)?;
                let s = scene.build_seconds();
                (Box::new(scene), s, Some(device.version()))
            }
            Backend::Rust => {
                let bvh = pool.install(|| Bvh::build(mesh));
                let s = bvh.build_seconds();
                (Box::new(bvh), s, None)
            }
        };
    bar.finish_and_clear();
    let sampler = ocean.sampler(cfg.camera.position_m);
    let objects = pool.install(|| {
        let r = lod.earth_radius_m;
        SceneObjects::build(
            &cfg.objects,
            &sampler,
            cfg.camera.position_m,
            r,
            cfg.render.backend,
            threads,
        )
    })?;
    let sky_irradiance = sky.irradiance();
    Ok(Prepared {
        ocean,
        lod,
        accel,
        seconds_build,
        embree_version,
        sky,
        skip_slope,
        skip_above_y,
        sky_irradiance,
        stats,
        seconds_ocean,
        seconds_tessellation,
        threads,
        pool,
        camera_position_m: cfg.camera.position_m,
        objects,
        object_configs: cfg.objects.clone(),
        backend: cfg.render.backend,
        mounted: None,
    })
}

/// Deepest trough counted on, in RMS heights: a Gaussian sea goes below -5 sigma at about one
/// point in 3.5 million.
const TROUGH_SIGMAS: f64 = 5.0;

impl Prepared {
    /// The y below which a camera ray's direction must meet the sea: the dip of the horizon of
    /// a sphere through the deepest troughs, as seen from `camera_height_m`. Flat triangles
    /// sag below the curved sea, by up to s^2 / 4R mid-hypotenuse for legs s (34 m for the
    /// 29 km triangles at a 10 km camera's horizon), so the sphere sits that much lower again. (A tessellation that stops short of
    /// that horizon leaves holes, and they are counted.)
    fn must_hit_below_y(&self, camera_height_m: f64) -> f32 {
        let r = self.lod.earth_radius_m;
        let horizon_m = (2.0 * r * camera_height_m).sqrt();
        let sag = self
            .stats
            .per_ring
            .iter()
            .filter(|ring| ring.inner_m <= 2.0 * horizon_m)
            .map(|ring| ring.size_m * ring.size_m / (4.0 * r))
            .fold(0.0, f64::max);
        let trough = TROUGH_SIGMAS * self.ocean.realization_rms_m() + sag;
        // cos(dip) = (R - trough) / (R + h); the direction's y is -sin(dip).
        let c = ((r - trough) / (r + camera_height_m)).min(1.0);
        -((1.0 - c * c).sqrt()) as f32
    }

    /// Traces the camera, samples and normal mode of `cfg` through the prepared scene. The
    /// ocean, LOD and sky sections of `cfg` are those `prepare` used; only `camera` (besides its
    /// position and height) and `render` may differ.
    pub fn render(&self, cfg: &SceneConfig, progress: bool) -> Result<Rendered, RenderError> {
        self.render_batches(cfg, 0, progress)
    }

    /// As [`Prepared::render`], keeping `batches` batch means per pixel (see
    /// [`super::film`]), which the error estimator needs.
    pub fn render_batches(
        &self,
        cfg: &SceneConfig,
        batches: usize,
        progress: bool,
    ) -> Result<Rendered, RenderError> {
        Ok(self
            .render_samples(cfg, batches, Samples::ALL, false, progress)?
            .0)
    }

    /// As [`Prepared::render_batches`], taking only `samples` of each pixel's (one pass of
    /// several, or more of some pixels' than others'), and returning each pixel's exact state as well when `keep_states` (what a
    /// pass file holds; empty otherwise).
    pub fn render_samples(
        &self,
        cfg: &SceneConfig,
        batches: usize,
        samples: Samples,
        keep_states: bool,
        progress: bool,
    ) -> Result<(Rendered, Vec<PixelState>), RenderError> {
        cfg.validate()?;
        let placed = self.placed_config(cfg)?;
        let cfg = placed.as_ref();
        let camera = Camera::new(cfg.camera.aimed(), cfg.camera.width, cfg.camera.aspect);
        let filtered = cfg.render.normals == crate::config::NormalMode::Filtered;
        super::limits::check_exact_levels(self.accel.as_ref(), cfg.render.normals)?;
        let levels = self.ocean.levels_built();
        check_memory(
            cfg,
            0,
            batches,
            keep_states,
            OceanAtHand::Prepared { levels },
        )?;
        let levels_start = Instant::now();
        let sampler = self.ocean.sampler(self.camera_position_m);
        // filtered normals read the layers' low-passed levels for the waves a footprint resolves
        let sampler = if filtered {
            sampler.with_levels(self.pool.install(|| self.ocean.levels()))
        } else {
            sampler
        };
        // the `mapped` lobe draws the normals the lookup would read, the `smith` lobe the sea's
        let slopes = filtered.then(|| {
            self.pool.install(|| match cfg.render.filter_lobe {
                crate::config::FilterLobe::Mapped => self.ocean.read_slopes(),
                crate::config::FilterLobe::Smith => self.ocean.slopes(),
            })
        });
        let seconds_levels = if filtered {
            levels_start.elapsed().as_secs_f64()
        } else {
            0.0
        };
        let scene_ref = SceneRef {
            slopes,
            // sampled at rough hits of filtered normals and at objects' hits
            sun: if filtered || self.objects.is_some() {
                self.sky.sun_light()
            } else {
                None
            },
            accel: self.accel.as_ref(),
            skip_slope: self.skip_slope,
            skip_above_y: self.skip_above_y,
            predict_camera_hits: !self.accel.exact_surface(),
            ocean: Some(sampler),
            earth_radius_m: self.lod.earth_radius_m,
            sky: &self.sky,
            objects: self.objects.as_ref(),
        };
        let mut settings = TraceSettings::new(cfg, self.sky_irradiance);
        settings.must_hit_below_y = self.must_hit_below_y(cfg.camera.height_m);
        let t = Instant::now();
        let (film, states, c) = self.pool.install(|| {
            render_image_samples(
                &scene_ref,
                &camera,
                cfg.camera.height_m as f32,
                cfg.render.spp,
                cfg.render.seed,
                &settings,
                batches,
                samples,
                keep_states,
                progress,
            )
        });
        let (h, aovs) = (cfg.camera.height_m as f32, &cfg.render.aovs);
        let aovs = (self.pool).install(|| scene_ref.aov_layers(&camera, h, aovs, &settings));
        let seconds_trace = t.elapsed().as_secs_f64();
        let objects_error = (self.objects.as_ref()).and_then(|o| o.take_error());
        if let Some(message) = self.accel.take_error().or(objects_error) {
            return Err(RenderError::Trace {
                backend: self.accel.name(),
                message,
            });
        }
        let sea_noise = self.pool.install(|| film.noise_rms_sea(&camera));
        let seconds_normal_map = c.normal_map_thread_seconds() / self.threads as f64;
        let folded_fraction = self.ocean.folded_fraction();
        let ocean_notes = self
            .ocean
            .spectrum()
            .map_or_else(Vec::new, |s| s.range_notes());
        let mut warnings = warnings(folded_fraction, c.escaped_below_horizon);
        if c.object_leaks > 0 {
            warnings.push(format!(
                "{} rays inside glass objects met none of their surface: a glass mesh must be \
                 closed and wound outward (counter-clockwise seen from outside)",
                c.object_leaks
            ));
        }
        let mesh = self.accel.mesh();
        let seconds_build = self.seconds_build;
        let seconds_objects = (self.objects.as_ref()).map_or(0.0, |o| o.build_seconds);
        let report = RenderReport {
            width: camera.width,
            height: camera.height,
            spp: cfg.render.spp,
            seed: cfg.render.seed,
            threads: self.threads,
            backend: self.accel.name().to_string(),
            embree_version: self.embree_version.clone(),
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            rings: self.stats.rings,
            mesh_bytes: mesh.bytes(),
            tessellation_max_distance_m: self.stats.max_distance_m,
            seconds_ocean: self.seconds_ocean,
            seconds_tessellation: self.seconds_tessellation,
            seconds_build,
            seconds_objects,
            seconds_levels,
            seconds_trace,
            seconds_normal_map,
            normal_map_share: seconds_normal_map / seconds_trace.max(1e-12),
            seconds_total: self.seconds_ocean
                + self.seconds_tessellation
                + seconds_build
                + seconds_objects
                + seconds_levels
                + seconds_trace,
            png_exposure_stops: None,
            rays: c.rays,
            mrays_per_s: c.rays as f64 / seconds_trace.max(1e-12) / 1e6,
            noise_rms: film.noise_rms(),
            noise_rms_relative: film.noise_rms().map(|n| n / mean_luminance(&film.image)),
            noise_rms_sea: sea_noise.map(|n| n.0),
            noise_rms_sea_relative: sea_noise.map(|n| n.1),
            nan_count: c.nan,
            folded_fraction,
            escaped_below_horizon: c.escaped_below_horizon,
            self_hits: c.self_hits,
            ocean_notes,
            warnings,
            rejected_rays: self.accel.rejected_rays(),
            wrong_side_count: c.wrong_side,
            backfacing_shading_count: c.backfacing_shading,
            truncated_paths: c.truncated,
            skip_slope: self.skip_slope,
            skipped_rays: c.skipped,
            skipped_rising_rays: c.skipped_rising,
            skip_above_y: self.skip_above_y,
            skipped_above_rays: c.skipped_above,
            sky_irradiance: self.sky_irradiance.to_array(),
            upwelling: cfg.water.upwelling(self.sky_irradiance).to_array(),
            counters: c,
            horizon_row_px: camera.horizon_rows(cfg.camera.height_m, self.lod.earth_radius_m),
            objects: (self.objects.as_ref())
                .map_or_else(Vec::new, |o| o.report_with(&aovs, camera.width)),
            passes: None,
            pass_file: None,
            exr: PathBuf::new(),
            png: PathBuf::new(),
            json: PathBuf::new(),
            config: cfg.clone(),
        };
        Ok((
            Rendered {
                film,
                camera,
                report,
                aovs,
            },
            states,
        ))
    }
}

/// Renders a validated scene end to end; `progress` shows a bar on stderr. Output paths are
/// filled in by [`write_outputs`].
pub fn render_scene(cfg: &SceneConfig, progress: bool) -> Result<Rendered, RenderError> {
    prepare_with(
        cfg,
        Setup {
            progress,
            ..Setup::default()
        },
    )?
    .render(cfg, progress)
}

#[path = "pipeline_frames.rs"]
mod frames;
#[path = "pipeline_mount.rs"]
mod mount;
pub use frames::FrameUpdate;
use mount::prepare_mounted;

#[cfg(test)]
#[path = "pipeline_tests.rs"]
mod tests;
