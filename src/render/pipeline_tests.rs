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

/// A boost of 0 leaves a pixel out (black, no variance, no rays): the pixels a render samples
/// are bit for bit those of a render of every pixel, so a pilot may trace only the rows that
/// are read from it.
#[test]
fn a_boost_of_zero_leaves_a_pixel_out_and_the_rest_unchanged() {
    use super::super::film::Samples;
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 48;
    cfg.render.spp = 3;
    cfg.render.threads = 2;
    cfg.render.backend = Backend::Rust;
    let p = prepare(&cfg).unwrap();
    let full = p.render(&cfg, false).unwrap();
    let (w, h) = (full.camera.width, full.camera.height);
    // the rows just below the horizon, and every other pixel of one of them twice over
    let mut boost = vec![0u16; w * h];
    boost[h / 2 * w..(h / 2 + 2) * w].fill(1);
    boost[h / 2 * w..(h / 2 + 1) * w]
        .iter_mut()
        .step_by(2)
        .for_each(|b| *b = 2);
    let samples = Samples {
        boost: Some(&boost),
        ..Samples::ALL
    };
    let (part, _) = p.render_samples(&cfg, 0, samples, false, false).unwrap();
    assert!(part.report.rays > 0 && part.report.rays < full.report.rays / 2);
    for (i, &b) in boost.iter().enumerate() {
        let (f, q) = (&full.film, &part.film);
        match b {
            0 => assert!(
                q.image.pixels[i] == [0.0; 3] && q.var_y[i] == 0.0,
                "pixel {i}"
            ),
            1 => {
                assert_eq!(q.image.pixels[i], f.image.pixels[i], "pixel {i}");
                assert_eq!(q.var_y[i], f.var_y[i], "pixel {i}");
            }
            // twice the samples: the first three are the full render's
            _ => assert!(q.image.pixels[i].iter().all(|c| c.is_finite()), "pixel {i}"),
        }
    }
}
