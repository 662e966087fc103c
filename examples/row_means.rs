//! Two renders of the same band, row by row: each row's mean luminance in A and B, their
//! difference, its standard error from the renders' own `Y.variance` (pixels independent), and
//! the band 0 to 5 degrees below the horizon as a whole, and every row below the horizon (the
//! whole sea, each pixel weighted by its solid angle). How docs/filtered.md compares filtered
//! and mapped normals:
//!
//! ```text
//! cargo run --release --example row_means -- A.exr B.exr ROW0
//! ```
//!
//! ROW0 is the band's first row in the full-sphere image (the equirectangular camera's
//! `row0`: floor((90 - top) / 180 x width / 2), 506 for +1:-6 at 2048 px). The standard error
//! trusts each pixel's sample variance, which under-states the error of pixels whose glints
//! few samples found: read a glint row's z with care.

use std::path::Path;
fn load(p: &str) -> (vastocean::image_io::RgbImage, Vec<f32>) {
    let p = Path::new(p);
    (
        vastocean::image_io::read_exr(p).unwrap(),
        vastocean::image_io::read_exr_channel(p, "Y.variance").unwrap(),
    )
}
fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 4 {
        eprintln!("usage: row_means A.exr B.exr ROW0");
        std::process::exit(2);
    }
    let (ia, va) = load(&a[1]);
    let (ib, vb) = load(&a[2]);
    let (w, h) = (ia.width, ia.height);
    let full_h = w / 2;
    let row0: f64 = a[3]
        .parse()
        .expect("ROW0: the band's first full-sphere row");
    let lum = |p: [f32; 3]| vastocean::color::luminance(p) as f64;
    let (mut sa, mut sb, mut sva, mut svb, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0);
    // the sea: rows below the horizon, weighted by cos(elevation) (a pixel's solid angle)
    let (mut ea, mut eb, mut eva, mut evb, mut en) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for y in 0..h {
        let el = 90.0 - (row0 + y as f64 + 0.5) * 180.0 / full_h as f64;
        let (mut ma, mut mb, mut vva, mut vvb) = (0.0, 0.0, 0.0, 0.0);
        for x in 0..w {
            let i = y * w + x;
            ma += lum(ia.pixels[i]);
            mb += lum(ib.pixels[i]);
            vva += va[i] as f64;
            vvb += vb[i] as f64;
        }
        let wf = w as f64;
        let (ma, mb) = (ma / wf, mb / wf);
        let se = ((vva + vvb) / (wf * wf)).sqrt();
        println!(
            "el {el:7.3}: a {ma:.5} b {mb:.5} diff {:+.5} se {:.5} z {:+.2} rel {:+.3}%",
            mb - ma,
            se,
            (mb - ma) / se,
            100.0 * (mb - ma) / ma
        );
        if el < 0.0 {
            let c = el.to_radians().cos();
            ea += c * ma;
            eb += c * mb;
            eva += c * c * vva / (wf * wf);
            evb += c * c * vvb / (wf * wf);
            en += c;
        }
        if el < 0.0 && el > -5.0 {
            sa += ma;
            sb += mb;
            sva += vva / (wf * wf);
            svb += vvb / (wf * wf);
            n += 1.0;
        }
    }
    total("band 0..-5:", (sa, sb), (sva, svb), n);
    if en > 0.0 {
        total("sea:      ", (ea, eb), (eva, evb), en);
    }
}

/// A weighted total of the rows of A and B: their means, the difference and its standard error.
fn total(label: &str, (a, b): (f64, f64), (va, vb): (f64, f64), n: f64) {
    let se = (va + vb).sqrt() / n;
    println!(
        "{label} a {:.5} b {:.5} diff {:+.5} se {:.5} z {:+.2} rel {:+.3}%",
        a / n,
        b / n,
        (b - a) / n,
        se,
        (b - a) / n / se,
        100.0 * (b - a) / a
    );
}
