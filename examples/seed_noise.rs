//! The sea's noise measured across renders that differ only in their sample seed, against the
//! noise each render's own `Y.variance` claims. How docs/filtered.md measures the standard error
//! of a pixel on the low-discrepancy pattern:
//!
//! ```text
//! cargo run --release --example seed_noise -- S1.exr S2.exr ... SN.exr [vs T1.exr ... TM.exr]
//! ```
//!
//! Each file is a full-sphere equirectangular render (width = 2 x height), or a band of rows
//! below the horizon (`render --band`), of the same scene, size and sample count with its own
//! `--seed`. For every pixel below the horizon (the lower half of a sphere's rows, every row
//! of a band) the variance of its luminance across the N renders is the variance of one
//! render's pixel, whatever the sampling pattern; `Y.variance` is the samples' variance over
//! their count, which takes the samples as independent and so over-states the variance of a
//! mean over a stratified pattern. Printed: the RMS over the sea's pixels of both standard
//! errors, their ratio, and each with a 95 % interval from the delete-one jackknife over the
//! renders. With a second set after `vs` (another scene or method, its own seeds), the same
//! for it and the ratio of the two sets' noise across the seeds, its interval from the two
//! jackknife variances of the logarithms (the sets are independent).

use std::path::Path;

/// Per-pixel sums over the renders: luminance, its square, and `Y.variance`.
struct Sums {
    s1: Vec<f64>,
    s2: Vec<f64>,
    v: Vec<f64>,
}

/// RMS standard error across the renders, leaving out render `skip` (if any).
fn across(sums: &Sums, lum: &[Vec<f32>], skip: Option<usize>) -> f64 {
    let n = (lum.len() - skip.is_some() as usize) as f64;
    let left_out = |i: usize| skip.map_or(0.0, |r| lum[r][i] as f64);
    let total: f64 = (sums.s1.iter().zip(&sums.s2).enumerate())
        .map(|(i, (&s1, &s2))| {
            let x = left_out(i);
            let (s1, s2) = (s1 - x, s2 - x * x);
            ((s2 - s1 * s1 / n) / (n - 1.0)).max(0.0)
        })
        .sum();
    (total / sums.s1.len() as f64).sqrt()
}

/// RMS of the renders' own standard errors (mean `Y.variance`), leaving out render `skip`.
fn claimed(sums: &Sums, var: &[Vec<f32>], skip: Option<usize>) -> f64 {
    let n = (var.len() - skip.is_some() as usize) as f64;
    let left_out = |i: usize| skip.map_or(0.0, |r| var[r][i] as f64);
    let total: f64 = (sums.v.iter().enumerate())
        .map(|(i, &v)| v - left_out(i))
        .sum();
    (total / (n * sums.v.len() as f64)).sqrt()
}

/// The statistic and its 95 % interval (delete-one jackknife, normal quantile).
fn jackknife(n: usize, full: f64, f: impl Fn(Option<usize>) -> f64) -> (f64, f64, f64) {
    let loo: Vec<f64> = (0..n).map(|r| f(Some(r))).collect();
    let m = loo.iter().sum::<f64>() / n as f64;
    let var = (n - 1) as f64 / n as f64 * loo.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    let se = var.sqrt();
    (full, full - 1.96 * se, full + 1.96 * se)
}

/// The sea's noise of one set of renders: across the seeds, claimed by `Y.variance`, and
/// their ratio, each as (value, low, high) (95 %).
fn measure(files: &[String]) -> [(f64, f64, f64); 3] {
    let (mut lum, mut var) = (Vec::new(), Vec::new());
    let mut size = None;
    for f in files {
        let p = Path::new(f);
        let img = vastocean::image_io::read_exr(p).unwrap_or_else(|e| panic!("{f}: {e}"));
        let v = vastocean::image_io::read_exr_channel(p, "Y.variance")
            .unwrap_or_else(|e| panic!("{f}: {e}"));
        let (w, h) = (img.width, img.height);
        if *size.get_or_insert((w, h)) != (w, h) {
            panic!("{f}: {w} x {h}: every render must be the same size");
        }
        // the sea: the lower half of the rows of a full sphere, every row of a band (`render
        // --band` below the horizon)
        let sea = if w == 2 * h {
            h / 2 * w..h * w
        } else {
            0..h * w
        };
        lum.push(
            img.pixels[sea.clone()]
                .iter()
                .map(|&p| vastocean::color::luminance(p))
                .collect::<Vec<f32>>(),
        );
        var.push(v[sea].to_vec());
    }
    let n = lum.len();
    let m = lum[0].len();
    let mut sums = Sums {
        s1: vec![0.0; m],
        s2: vec![0.0; m],
        v: vec![0.0; m],
    };
    for (l, v) in lum.iter().zip(&var) {
        for i in 0..m {
            let x = l[i] as f64;
            sums.s1[i] += x;
            sums.s2[i] += x * x;
            sums.v[i] += v[i] as f64;
        }
    }
    let a = jackknife(n, across(&sums, &lum, None), |s| across(&sums, &lum, s));
    let c = jackknife(n, claimed(&sums, &var, None), |s| claimed(&sums, &var, s));
    let r = jackknife(n, a.0 / c.0, |s| {
        across(&sums, &lum, s) / claimed(&sums, &var, s)
    });
    println!("renders {n}, sea pixels {m}");
    println!("  across the seeds: {:.5} [{:.5}, {:.5}]", a.0, a.1, a.2);
    println!("  Y.variance:       {:.5} [{:.5}, {:.5}]", c.0, c.1, c.2);
    println!("  ratio:            {:.3} [{:.3}, {:.3}]", r.0, r.1, r.2);
    [a, c, r]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut sets = args.split(|a| a == "vs");
    let first = sets.next().unwrap_or_default();
    let second = sets.next();
    if first.len() < 3 || second.is_some_and(|s| s.len() < 3) || sets.next().is_some() {
        eprintln!("usage: seed_noise S1.exr S2.exr S3.exr [...] [vs T1.exr T2.exr T3.exr [...]]");
        eprintln!("       (three renders or more in each set)");
        std::process::exit(2);
    }
    let a = measure(first);
    if let Some(second) = second {
        let b = measure(second);
        // log-scale standard errors back from the 95 % intervals
        let se = |x: (f64, f64, f64)| (x.2 - x.1) / (2.0 * 1.96 * x.0);
        let (ratio, se) = (a[0].0 / b[0].0, se(a[0]).hypot(se(b[0])));
        println!(
            "across the seeds, first / second: {ratio:.3} [{:.3}, {:.3}]",
            ratio * (-1.96 * se).exp(),
            ratio * (1.96 * se).exp()
        );
    }
}
