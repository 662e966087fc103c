//! A camera an object carries (`camera.mount`): the scene prepared around the place the
//! object's pose puts it, and renders of that scene from there.

use std::borrow::Cow;

use super::*;

/// [`prepare_with`] for a scene whose camera an object carries: the ocean first, then the
/// camera on the object's pose at the ocean's time, then the scene around it.
pub(super) fn prepare_mounted(cfg: &SceneConfig, setup: Setup) -> Result<Prepared, RenderError> {
    cfg.validate()?;
    let (ocean, seconds_ocean) = match setup.ocean {
        Some(ocean) => (ocean, 0.0),
        None => {
            // The ocean is built here, before the camera's place (and so the tessellation) is
            // known: it is checked alone now, the mesh by `prepare_with` once it is built.
            check_memory(
                cfg,
                0,
                crate::render::film::MAX_BATCHES,
                false,
                OceanAtHand::None,
            )?;
            tracing_pool(cfg.render.threads)?.install(|| build_ocean(cfg, setup.progress))?
        }
    };
    let mut placed = cfg.clone();
    placed.camera = crate::objects::mount::mounted_camera(&cfg.camera, &cfg.objects, &ocean)?;
    let surface_m = surface_height_at_nadir(&ocean.sampler(placed.camera.position_m));
    if placed.camera.height_m <= surface_m {
        return Err(RenderError::CameraUnderwater {
            camera_m: placed.camera.height_m,
            surface_m,
        });
    }
    // a sky handed in was built for the free camera's height, which its dome's parallax uses
    let sky = setup.sky.and_then(|mut sky| {
        let h = placed.camera.height_m;
        if let Some(own) = Arc::get_mut(&mut sky) {
            own.camera_height_m = h;
        }
        (sky.camera_height_m == h).then_some(sky)
    });
    let mut prepared = prepare_with(
        &placed,
        Setup {
            ocean: Some(ocean),
            sky,
            ..setup
        },
    )?;
    prepared.seconds_ocean += seconds_ocean;
    prepared.mounted = Some(placed.camera);
    Ok(prepared)
}

impl Prepared {
    /// `cfg` as this prepared scene renders it: with the camera its mount placed (the
    /// prepared one's place and aim, `cfg`'s image size), or as it is for a free camera; a
    /// mounted scene and a free camera (or the other way round) do not mix.
    pub(super) fn placed_config<'a>(
        &self,
        cfg: &'a SceneConfig,
    ) -> Result<Cow<'a, SceneConfig>, RenderError> {
        match (&cfg.camera.mount, &self.mounted) {
            (None, None) => Ok(Cow::Borrowed(cfg)),
            (None, Some(_)) => Err(RenderError::SharedOcean(
                "was prepared around a mounted camera; this scene's camera is free",
            )),
            (Some(_), Some(camera)) => Ok(Cow::Owned(SceneConfig {
                camera: crate::config::CameraConfig {
                    width: cfg.camera.width,
                    aspect: cfg.camera.aspect,
                    ..camera.clone()
                },
                ..cfg.clone()
            })),
            (Some(_), None) => Err(RenderError::SharedOcean(
                "was prepared for a free camera; this scene's camera is mounted",
            )),
        }
    }
}
