use super::*;

#[test]
fn the_rust_backend_renders_the_default_scene_with_or_without_embree() {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 64;
    cfg.render.spp = 1;
    cfg.render.threads = 2;
    cfg.render.backend = Backend::Rust;
    let r = render_scene(&cfg, false).unwrap();
    assert_eq!(r.report.backend, "rust");
    assert!(r.report.triangles > 1000 && r.report.rays > 0 && r.report.nan_count == 0);
    assert!(
        r.film
            .image
            .pixels
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0))
    );
    let mut embree = cfg.clone();
    embree.render.backend = Backend::Embree;
    let e = render_scene(&embree, false);
    if cfg!(feature = "embree") {
        assert_eq!(e.unwrap().report.triangles, r.report.triangles);
    } else {
        assert!(matches!(e, Err(RenderError::NoEmbree)));
    }
}

/// A scene handed an ocean prepares on it without building another (its report says 0 s
/// for the ocean) and renders the same image as one that builds its own; an ocean of
/// another seed is refused, and a shared ocean cannot be moved to another time.
#[test]
fn a_shared_ocean_is_used_as_built_and_refused_where_it_does_not_fit() {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 32;
    cfg.render.spp = 1;
    cfg.render.threads = 2;
    cfg.render.backend = Backend::Rust;
    let own = prepare(&cfg).unwrap();
    let shared = |cfg: &SceneConfig| {
        prepare_with(
            cfg,
            Setup {
                ocean: Some(Arc::clone(&own.ocean)),
                ..Setup::default()
            },
        )
    };
    let mut second = shared(&cfg).unwrap();
    assert!(Arc::ptr_eq(&own.ocean, &second.ocean));
    assert_eq!(second.seconds_ocean, 0.0);
    let (a, b) = (
        own.render(&cfg, false).unwrap(),
        second.render(&cfg, false).unwrap(),
    );
    assert_eq!(a.film.image.pixels, b.film.image.pixels);
    assert!(matches!(
        second.advance_to(1.0, cfg.camera.height_m),
        Err(RenderError::SharedOcean(_))
    ));
    let mut other = cfg.clone();
    other.render.ocean_seed += 1;
    assert!(matches!(shared(&other), Err(RenderError::SharedOcean(_))));
}
