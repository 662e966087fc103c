//! Equirectangular sky maps: validation, bilinear lookups (alone and in lanes) and irradiance.

use std::path::Path;

use glam::Vec3;

use crate::equirect;
use crate::image_io::{ImageError, RgbImage};

/// Cosine-weighted integral of an equirectangular map over the upper hemisphere: each texel
/// contributes L sin(elevation) times its solid angle cos(elevation) dphi dtheta.
pub fn map_irradiance(img: &RgbImage) -> Vec3 {
    let (dphi, dtheta) = (
        std::f64::consts::TAU / img.width as f64,
        std::f64::consts::PI / img.height as f64,
    );
    let mut e = [0f64; 3];
    for y in 0..img.height / 2 {
        let el = std::f64::consts::FRAC_PI_2 - (y as f64 + 0.5) * dtheta;
        let w = el.sin() * el.cos() * dphi * dtheta;
        for x in 0..img.width {
            let p = img.get(x, y);
            for k in 0..3 {
                e[k] += p[k] as f64 * w;
            }
        }
    }
    Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)
}

/// Checks that an image can serve as an equirectangular sky map.
pub fn validate_map(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    let invalid = |message: String| ImageError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    if img.width != 2 * img.height || img.height < 2 {
        return Err(invalid(format!(
            "a sky map must be equirectangular (width = 2 x height), got {} x {}",
            img.width, img.height
        )));
    }
    // (0 <= c <= MAX is false for NaN, infinities and negatives.) A branch-free pass the
    // compiler vectorises, then the search for the first bad texel only where there is one:
    // searching with a short-circuit on every texel took 10 ms of a 2048 x 1024 map's load,
    // and in parallel 20 ms (the global thread pool's start-up).
    let valid = |c: f32| (0.0..=f32::MAX).contains(&c);
    let all_valid = img
        .pixels
        .chunks(1024)
        .all(|chunk| chunk.iter().flatten().fold(true, |ok, &c| ok & valid(c)));
    if let Some(i) = (!all_valid)
        .then(|| img.pixels.iter().position(|p| !p.iter().all(|&c| valid(c))))
        .flatten()
    {
        return Err(invalid(format!(
            "texel ({}, {}) is {:?}: sky radiance must be finite and >= 0",
            i % img.width,
            i / img.width,
            img.pixels[i]
        )));
    }
    Ok(())
}

/// Bilinear lookup of an equirectangular map along `d` (any non-zero length), wrapping in
/// azimuth and clamping at the poles.
pub fn lookup(img: &RgbImage, d: Vec3) -> Vec3 {
    Vec3::from(read_taps(img, &taps(d.to_array(), img.width, img.height)))
}

/// Where a bilinear lookup reads: columns `xa`, `xb` (wrapped), rows `ya`, `yb` (clamped) and
/// the weights of `xb` and `yb`.
#[derive(Clone, Copy, Default)]
pub(super) struct Taps {
    xa: u32,
    xb: u32,
    ya: u32,
    yb: u32,
    fx: f32,
    fy: f32,
}

/// The taps of a `w` x `h` map along `d`: one lane of a batch ([`Sky::radiance_many`] runs it
/// over many directions in a loop the compiler vectorises; [`lookup`] runs it alone, so a
/// direction reads the same texels with the same weights either way). The floors are written
/// as truncations, which vectorise without SSE4.1 (a lane of NaN reads columns 0 and 1 of row
/// 0, weighted NaN).
#[inline(always)]
pub(super) fn taps(d: [f32; 3], w: usize, h: usize) -> Taps {
    let (wf, hf) = (w as f32, h as f32);
    // Continuous pixel coordinates; texel centres sit at +0.5.
    let (x, y) = equirect::direction_pixel(Vec3::from(d), wf, hf);
    let x = x - 0.5;
    let y = (y - 0.5).clamp(0.0, hf - 1.0);
    // floor(x) for x in [-0.5, w - 0.5]; y >= 0 truncates to its floor
    let t = x as i32;
    let x0 = t - i32::from(x < t as f32);
    let y0 = y as i32;
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let (wi, hi) = (w as i32, h as i32);
    let xa = if x0 < 0 { x0 + wi } else { x0 };
    let xb = if x0 + 1 >= wi { x0 + 1 - wi } else { x0 + 1 };
    let clamp = |i: i32, n: i32| i.clamp(0, n - 1) as u32;
    Taps {
        xa: clamp(xa, wi),
        xb: clamp(xb, wi),
        ya: clamp(y0, hi),
        yb: clamp(y0 + 1, hi),
        fx,
        fy,
    }
}

/// The bilinear blend of a lookup's four texels.
#[inline(always)]
pub(super) fn read_taps(img: &RgbImage, t: &Taps) -> [f32; 3] {
    read_taps_by(t, |x, y| img.get(x as usize, y as usize))
}

/// [`read_taps`] of the texels `p(column, row)` gives.
#[inline(always)]
pub(super) fn read_taps_by(t: &Taps, p: impl Fn(u32, u32) -> [f32; 3]) -> [f32; 3] {
    let (a, b, c, d) = (p(t.xa, t.ya), p(t.xb, t.ya), p(t.xa, t.yb), p(t.xb, t.yb));
    let (fx, fy) = (t.fx, t.fy);
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}
