//! Moving a prepared scene to another ocean time, as an animation's frames do: the mesh
//! displaced anew and its BVH refitted, or, for a camera an object carries, the scene prepared
//! anew around the camera's new place.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::*;

/// What moving a prepared scene to another ocean time cost, seconds.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct FrameUpdate {
    /// The layers' fields at the new time (eq. 2 and the FFTs).
    pub seconds_ocean: f64,
    /// Every vertex's position and normal from its texture coordinate, and the mesh's
    /// steepest slope (which the ray skipping needs).
    pub seconds_geometry: f64,
    /// The BVH's update over the moved vertices (Embree's refit, the Rust BVH's bounds).
    pub seconds_refit: f64,
}

impl Prepared {
    /// Moves the ocean to `time_s` and the mesh with it: the tessellation's topology stays
    /// (it depends on the camera only), every vertex is displaced anew from its texture
    /// coordinate and the BVH is refitted. Refuses, as [`prepare`] does, a sea that folds too
    /// much or stands above the camera at that time.
    pub fn advance_to(
        &mut self,
        time_s: f64,
        camera_height_m: f64,
    ) -> Result<FrameUpdate, RenderError> {
        let t = Instant::now();
        let ocean = Arc::get_mut(&mut self.ocean).ok_or(RenderError::SharedOcean(
            "cannot move to another time: prepare the animation with an ocean of its own",
        ))?;
        let folded = self.pool.install(|| -> Result<f64, RenderError> {
            ocean.set_time(time_s)?;
            Ok(ocean.folded_fraction())
        })?;
        let seconds_ocean = t.elapsed().as_secs_f64();
        if folded > MAX_FOLDED_FRACTION {
            return Err(RenderError::Folded {
                folded,
                choppiness: self.ocean.params().choppiness,
            });
        }
        let sampler = self.ocean.sampler(self.camera_position_m);
        let surface_m = surface_height_at_nadir(&sampler);
        if camera_height_m <= surface_m {
            return Err(RenderError::CameraUnderwater {
                camera_m: camera_height_m,
                surface_m,
            });
        }
        let t = Instant::now();
        let earth_r = self.lod.earth_radius_m;
        let (positions, normals) = self
            .pool
            .install(|| crate::lod::displace(self.accel.mesh().uvs(), &sampler, earth_r));
        let accel = &mut self.accel;
        let seconds_refit = self
            .pool
            .install(|| accel.update_vertices(&positions, &normals))
            .map_err(|message| RenderError::Refit {
                backend: self.accel.name(),
                message,
            })?;
        drop((positions, normals));
        let mesh = self.accel.mesh();
        (self.skip_slope, self.skip_above_y) = self
            .pool
            .install(|| (max_slope(mesh), highest_vertex_y(mesh)));
        if self.object_configs.iter().any(|o| o.float) {
            let (r, cam, threads) = (earth_r, self.camera_position_m, self.threads);
            let configs = &self.object_configs;
            let backend = self.backend;
            self.objects = self
                .pool
                .install(|| SceneObjects::build(configs, &sampler, cam, r, backend, threads))?;
        }
        let seconds_geometry = t.elapsed().as_secs_f64() - seconds_refit;
        Ok(FrameUpdate {
            seconds_ocean,
            seconds_geometry,
            seconds_refit,
        })
    }
}

impl Prepared {
    /// [`Prepared::advance_to`] for a scene whose camera an object carries
    /// (`camera.mount`): the camera moves with the object, and the tessellation, which is
    /// built around the camera, with it; so the ocean moves to `time_s` and the scene of `cfg`
    /// is prepared anew around the camera's new place (a new tessellation and BVH, where a
    /// free camera's frame refits). The ocean and the sky are kept.
    pub fn remount_to(
        self,
        cfg: &SceneConfig,
        time_s: f64,
    ) -> Result<(Prepared, FrameUpdate), RenderError> {
        let t = Instant::now();
        let Prepared {
            mut ocean,
            sky,
            pool,
            ..
        } = self;
        let own = Arc::get_mut(&mut ocean).ok_or(RenderError::SharedOcean(
            "cannot move to another time: prepare the animation with an ocean of its own",
        ))?;
        pool.install(|| own.set_time(time_s))?;
        drop(pool);
        let seconds_ocean = t.elapsed().as_secs_f64();
        let mut at = cfg.clone();
        at.ocean.time_s = time_s;
        let prepared = prepare_with(
            &at,
            Setup {
                // (each frame is built anew: nothing is refitted)
                refittable: false,
                progress: false,
                ocean: Some(ocean),
                sky: Some(sky),
            },
        )?;
        let update = FrameUpdate {
            seconds_ocean,
            seconds_geometry: prepared.seconds_tessellation,
            seconds_refit: prepared.seconds_build,
        };
        Ok((prepared, update))
    }
}
