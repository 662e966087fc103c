//! The sun's glitter seen from far above, where every pixel covers many waves, against the
//! closed form of a sea with Gaussian slopes (Cox & Munk 1954): the radiance a rough surface
//! reflects from a small bright source is
//!
//!   L = F(v.h) p(slope of h) E_sun / (4 cos(theta_v) cos^4(theta_h))
//!
//! with p the slopes' Gaussian density, h the half vector and E_sun the disc's irradiance on a
//! plane facing it (integrated over the disc here), and Smith's masking, which at these angles
//! is 1 to many digits. That is the `smith` lobe's model. The `mapped` lobe draws the normals by
//! area, as normal mapping on a flat triangle has them, and reflects
//!
//!   L = F(v.h) p(slope of h) E_sun / (4 (v.h) cos^3(theta_h)),
//!
//! the same at the specular centre, different off it: mapped normals do not weigh a facet by the
//! area it shows the camera. The slopes' covariance is the realization's (the slope tables'
//! total, checked against the grid by Parseval in the ocean's tests) for Cox & Munk's, and the
//! realization's as the lookup reads it (checked against the reads there) for normal mapping's;
//! the waves are linear (no choppiness), so their slopes are Gaussian.

use glam::DVec3;
use vastocean::config::{AnalyticSky, FilterLobe, SceneConfig};
use vastocean::render::Camera;
use vastocean::render::pipeline::prepare;
use vastocean::sky::{SUN_RADIUS_RAD, SkySource};

/// The scene `scenes/far-field-glitter.toml` (the default sea state without choppiness, at its
/// realization's own height, seen from 3 km up, 40 degrees down towards a sun 40 degrees up at
/// infinity, a black sky around it and no water-leaving light) 64 pixels wide: each pixel spans
/// 16 mrad, some 70 m of sea, and the footprint leaves out all but the longest swell's slopes.
fn scene(lobe: FilterLobe, spp: u32) -> SceneConfig {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/far-field-glitter.toml");
    let mut cfg = SceneConfig::load(&path).unwrap();
    cfg.camera.width = 64;
    cfg.render.filter_lobe = lobe;
    cfg.render.spp = spp;
    cfg
}

/// What the closed form needs of the scene.
#[derive(Clone)]
struct Setting {
    height_m: f64,
    ior: f64,
    /// The slope covariance (xx, xz, zz): the realization's, or as the lookup reads it.
    cov: [f64; 3],
    /// The sun as points: each direction with its luminance times the solid angle it stands for.
    sun: Vec<(DVec3, f64)>,
    /// Cox & Munk's form with Smith's masking (the `smith` lobe), or the normals by area
    /// (the `mapped` lobe).
    smith: bool,
}

/// Unpolarised Fresnel reflectance of air to water (index `ior`) at incidence cosine `c`.
fn fresnel(c: f64, ior: f64) -> f64 {
    let s = (1.0 - c * c).max(0.0).sqrt() / ior;
    let ct = (1.0 - s * s).sqrt();
    let rs = (c - ior * ct) / (c + ior * ct);
    let rp = (ior * c - ct) / (ior * c + ct);
    0.5 * (rs * rs + rp * rp)
}

/// Smith's Lambda of a Gaussian slope distribution with covariance `cov` for direction `w`
/// (local frame, +y up): the slopes' std along w's azimuth sets a = cot(theta) / (sqrt 2 std).
fn smith_lambda(w: DVec3, cov: [f64; 3]) -> f64 {
    let horizontal = (w.x * w.x + w.z * w.z).sqrt();
    if horizontal == 0.0 {
        return 0.0;
    }
    let (c, s) = (w.x / horizontal, w.z / horizontal);
    let std = (c * c * cov[0] + 2.0 * c * s * cov[1] + s * s * cov[2]).sqrt();
    let a = w.y / horizontal / (std::f64::consts::SQRT_2 * std);
    0.5 * ((-a * a).exp() / (a * std::f64::consts::PI.sqrt()) - erfc(a))
}

/// The complementary error function for x >= 0 (Abramowitz & Stegun 7.1.26, within 1.5e-7).
fn erfc(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.3275911 * x);
    let poly = t
        * (0.254829592
            + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    poly * (-x * x).exp()
}

/// The closed-form luminance seen along `dir` from the camera: the disc integrated over a grid
/// of points, each reflected by the slope that sends it along `dir`, in the frame of the local
/// vertical where `dir` meets the curved sea.
fn closed_form(dir: DVec3, set: &Setting) -> f64 {
    let cov = set.cov;
    let r_earth = 6_371_000.0;
    let centre = DVec3::new(0.0, -r_earth, 0.0);
    let org = DVec3::new(0.0, set.height_m, 0.0);
    // Where the ray meets the sphere, and the rotation taking its vertical to +y.
    let oc = org - centre;
    let b = oc.dot(dir);
    let t = -b - (b * b - (oc.length_squared() - r_earth * r_earth)).sqrt();
    let up = (org + t * dir - centre).normalize();
    let axis = up.cross(DVec3::Y);
    let to_local = |w: DVec3| {
        if axis.length() < 1e-15 {
            return w;
        }
        let a = axis.normalize();
        let (s, c) = (axis.length(), up.dot(DVec3::Y));
        w * c + a.cross(w) * s + a * a.dot(w) * (1.0 - c)
    };
    let v = to_local(-dir);
    let det = cov[0] * cov[2] - cov[1] * cov[1];
    let mut sum = 0.0;
    for &(l, weight) in &set.sun {
        let l = to_local(l);
        let h = (v + l).normalize();
        let (zx, zz) = (-h.x / h.y, -h.z / h.y);
        // Gaussian density of the slope (zx, zz) with covariance (xx, xz, zz).
        let q = (cov[2] * zx * zx - 2.0 * cov[1] * zx * zz + cov[0] * zz * zz) / det;
        let p = (-0.5 * q).exp() / (2.0 * std::f64::consts::PI * det.sqrt());
        let vh = v.dot(h);
        let value = if set.smith {
            let masking = 1.0 / ((1.0 + smith_lambda(v, cov)) * (1.0 + smith_lambda(l, cov)));
            masking / (4.0 * v.y * h.y.powi(4))
        } else {
            1.0 / (4.0 * vh * h.y.powi(3))
        };
        sum += weight * fresnel(vh, set.ior) * p * value;
    }
    sum
}

/// The analytic sun's disc as points on a grid across it, luminance `l` each.
fn disc_points(sun: DVec3, l: f64) -> Vec<(DVec3, f64)> {
    let u1 = DVec3::Y.cross(sun).normalize();
    let u2 = sun.cross(u1);
    let r = SUN_RADIUS_RAD as f64;
    const GRID: i32 = 24;
    let points: Vec<DVec3> = (0..GRID * GRID)
        .map(|k| {
            let a = 2.0 * ((k % GRID) as f64 + 0.5) / GRID as f64 - 1.0;
            let b = 2.0 * ((k / GRID) as f64 + 0.5) / GRID as f64 - 1.0;
            (a, b)
        })
        .filter(|(a, b)| a * a + b * b <= 1.0)
        .map(|(a, b)| (sun + r * (a * u1 + b * u2)).normalize())
        .collect();
    let disc_sr = 2.0 * std::f64::consts::PI * (1.0 - r.cos());
    let each = l * disc_sr / points.len() as f64;
    points.into_iter().map(|d| (d, each)).collect()
}

/// A map's sun as its lit texels above the horizon (the sky around it is black).
fn map_points(img: &vastocean::image_io::RgbImage) -> Vec<(DVec3, f64)> {
    use vastocean::equirect::{column_azimuth, direction64, row_elevation, texel_solid_angle};
    let (w, h) = (img.width, img.height);
    let mut points = Vec::new();
    for j in 0..h / 2 {
        for i in 0..w {
            let l = vastocean::color::luminance(img.get(i, j)) as f64;
            if l > 0.0 {
                let d = direction64(row_elevation(j, h), column_azimuth(i, w));
                points.push((d, l * texel_solid_angle(j, w, h)));
            }
        }
    }
    points
}

/// One block of 8 x 8 pixels down the sun's column: its first row, the rendered mean luminance
/// and its standard error, and the two closed forms averaged over the same pixels.
struct Block {
    row: usize,
    rendered: f64,
    se: f64,
    cox_munk: f64,
    by_area: f64,
}

/// Renders `cfg` and compares it block by block with both closed forms.
fn blocks(cfg: &SceneConfig) -> Vec<Block> {
    let p = prepare(cfg).unwrap();
    let AnalyticSky::HandMadeClear {
        sun_elevation_deg,
        sun_azimuth_deg,
        ..
    } = cfg.sky.analytic
    else {
        panic!("the scene's sky is the hand-made one")
    };
    let sun = vastocean::equirect::direction64(
        (sun_elevation_deg as f64).to_radians(),
        (sun_azimuth_deg as f64).to_radians(),
    );
    let sun = match &p.sky.source {
        SkySource::Map(img) => map_points(img),
        SkySource::Analytic { .. } => {
            let l = p.sky.radiance(glam::Vec3::ZERO, sun.as_vec3()).to_array();
            disc_points(sun, vastocean::color::luminance(l) as f64)
        }
    };
    let smith = Setting {
        height_m: cfg.camera.height_m,
        ior: cfg.water.ior as f64,
        cov: p.ocean.slopes().total(),
        sun,
        smith: true,
    };
    // the `mapped` lobe's slopes are the ones the lookup reads
    let by_area = Setting {
        smith: false,
        cov: p.ocean.read_slopes().total(),
        ..smith.clone()
    };
    eprintln!(
        "slope covariance (xx, xz, zz) {:?}, mss {:.5}; as read {:?}, mss {:.5}",
        smith.cov,
        smith.cov[0] + smith.cov[2],
        by_area.cov,
        by_area.cov[0] + by_area.cov[2]
    );
    let r = p.render(cfg, false).unwrap();
    let camera = Camera::new(cfg.camera.projection, cfg.camera.width, cfg.camera.aspect);
    let (w, h) = (camera.width, camera.height);
    let mut out = Vec::new();
    for row in (0..h).step_by(8) {
        let mut b = Block {
            row,
            rendered: 0.0,
            se: 0.0,
            cox_munk: 0.0,
            by_area: 0.0,
        };
        for y in row..row + 8 {
            for x in w / 2 - 4..w / 2 + 4 {
                let i = y * w + x;
                b.rendered += vastocean::color::luminance(r.film.image.pixels[i]) as f64 / 64.0;
                b.se += r.film.var_y[i] as f64 / (64.0 * 64.0);
                // The closed forms over a 3 x 3 grid of the pixel's positions.
                for (sx, sy) in (0..9).map(|k| (k % 3, k / 3)) {
                    let d = camera
                        .direction(
                            x as f32 + (sx as f32 + 0.5) / 3.0,
                            y as f32 + (sy as f32 + 0.5) / 3.0,
                        )
                        .as_dvec3();
                    b.cox_munk += closed_form(d, &smith) / (9.0 * 64.0);
                    b.by_area += closed_form(d, &by_area) / (9.0 * 64.0);
                }
            }
        }
        b.se = b.se.sqrt();
        out.push(b);
    }
    out
}

/// Renders the scene with `lobe` at 16 spp and checks it against its own closed form: blocks
/// that hold the glitter (a tenth of its peak and up) within 1 % plus four standard errors,
/// the tails within a thousandth of the peak plus four. The other closed form must be many
/// standard errors away in some block, or the check could not tell the two models apart.
fn check(cfg: &SceneConfig) {
    let lobe = cfg.render.filter_lobe;
    let blocks = blocks(cfg);
    let own = |b: &Block| match lobe {
        FilterLobe::Smith => (b.cox_munk, b.by_area),
        FilterLobe::Mapped => (b.by_area, b.cox_munk),
    };
    let peak = blocks.iter().map(|b| own(b).0).fold(0.0, f64::max);
    for b in &blocks {
        let (expected, other) = own(b);
        eprintln!(
            "{lobe:?} rows {:2}-{:2}: rendered {:.5e} +- {:.1e}, closed form {expected:.5e} \
             (ratio {:.4}), the other model's {other:.5e}",
            b.row,
            b.row + 7,
            b.rendered,
            b.se,
            b.rendered / expected
        );
    }
    for b in &blocks {
        let (expected, _) = own(b);
        let tolerance = if expected > 0.1 * peak {
            0.01 * expected
        } else {
            1e-3 * peak
        } + 4.0 * b.se;
        assert!(
            (b.rendered - expected).abs() < tolerance,
            "{lobe:?} rows {}..{}: rendered {} +- {}, closed form {expected}",
            b.row,
            b.row + 8,
            b.rendered,
            b.se
        );
    }
    assert!(
        blocks
            .iter()
            .any(|b| (b.rendered - own(b).1).abs() > 0.05 * own(b).0 + 20.0 * b.se),
        "{lobe:?}: the two closed forms are too close here to tell the models apart"
    );
}

#[test]
fn the_smith_lobe_glitter_is_cox_and_munk_s() {
    check(&scene(FilterLobe::Smith, 16));
}

#[test]
fn the_mapped_lobe_glitter_is_normal_mapping_s() {
    check(&scene(FilterLobe::Mapped, 16));
}

#[test]
fn a_sky_maps_sun_is_sampled_too() {
    // The same sky rasterized into a 2048-wide map (its disc a few texels): the map's sun is
    // found and sampled, and the glitter is the closed form of those texels.
    let mut cfg = scene(FilterLobe::Smith, 16);
    cfg.render.sun_samples = 1;
    check_under_map(cfg, "one");
}

/// [`check`] with the scene's analytic sky rasterized into a 2048-wide map, written to a
/// folder of the test's own (`name`).
fn check_under_map(mut cfg: SceneConfig, name: &str) {
    let map = vastocean::sky::rasterize(&cfg.sky.analytic, 2048);
    let dir =
        std::env::temp_dir().join(format!("vastocean-far-field-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sun.exr");
    vastocean::image_io::write_exr(&path, &map).unwrap();
    cfg.sky.file = Some(path);
    check(&cfg);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_mapped_lobe_glitter_near_the_horizon_under_terminate() {
    // A sun 8 degrees up and the camera 33 degrees down: the glitter lies 3 to 14 degrees below
    // the horizon, where a fifth of the normals the lobe draws (under the default `terminate`)
    // face away from the ray and end their paths. The normals that reflect the sun all face
    // it, so the glitter keeps its closed form: the sun's samples stand for the whole lobe,
    // whatever becomes of the normal drawn beside them.
    let mut cfg = scene(FilterLobe::Mapped, 16);
    assert_eq!(
        cfg.render.wrong_side,
        vastocean::config::WrongSide::Terminate
    );
    if let AnalyticSky::HandMadeClear {
        sun_elevation_deg, ..
    } = &mut cfg.sky.analytic
    {
        *sun_elevation_deg = 8.0;
    }
    if let vastocean::config::Projection::Pinhole { pitch_deg, .. } = &mut cfg.camera.projection {
        *pitch_deg = -33.0;
    }
    check(&cfg);
}

#[test]
fn several_sun_samples_on_a_lattice_give_the_same_glitter() {
    // A rough hit whose lobe may reflect the sun samples its disc `sun_samples` times and traces
    // one shadow ray among them, chosen by contribution; the multiple-importance weights count
    // the samples. Both lobes with one sample and with counts that are not powers of two, and
    // the map's sun, whose points run over its texels instead of a cone: the glitter keeps its
    // closed form.
    for (lobe, k) in [
        (FilterLobe::Smith, 1),
        (FilterLobe::Smith, 3),
        (FilterLobe::Mapped, 1),
        (FilterLobe::Mapped, 5),
    ] {
        let mut cfg = scene(lobe, 16);
        cfg.render.sun_samples = k;
        check(&cfg);
    }
    let mut cfg = scene(FilterLobe::Smith, 16);
    cfg.render.sun_samples = 6;
    check_under_map(cfg, "several");
}
