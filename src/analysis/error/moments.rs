//! What the estimator reads from the films, once: for every scenario, analysed row and azimuth
//! block, the sums and cross products of the batch differences D_b = Y_S,b - Y_0,b over the
//! block's pixels. Every statistic, the point estimate and each bootstrap replicate alike, is
//! a weighted sum of these (see [`RowSums::add_weighted`]).

use rayon::prelude::*;

use super::{BLOCK_DEG, EstimateError, Inputs, TREND_DEG};
use crate::render::film::{Batches, MAX_BATCHES};

/// Most batches a film keeps.
pub(super) const K: usize = MAX_BATCHES;

/// Sums over one block of one batch-difference field: S_b = sum_x D_b(x) and the cross
/// products G_bc = sum_x D_b(x) D_c(x).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Gram {
    pub s: [f64; K],
    pub g: [[f64; K]; K],
}

impl Gram {
    fn add(&mut self, d: &[f64], k: usize) {
        for b in 0..k {
            self.s[b] += d[b];
            for c in b..k {
                self.g[b][c] += d[b] * d[c];
            }
        }
    }

    fn symmetrise(&mut self, k: usize) {
        for b in 0..k {
            for c in 0..b {
                self.g[b][c] = self.g[c][b];
            }
        }
    }
}

/// One block of one row of one scenario: its pixel count and the moments of the difference,
/// of its smooth azimuthal trend and of the residual detail (each batch's difference is split
/// by the same moving average, so the split keeps the batches independent).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BlockMoments {
    pub n: f64,
    pub d: Gram,
    pub trend: Gram,
    pub residual: Gram,
}

/// Which field of a block's moments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Field {
    Difference,
    Trend,
    Residual,
}

impl BlockMoments {
    pub fn field(&self, f: Field) -> &Gram {
        match f {
            Field::Difference => &self.d,
            Field::Trend => &self.trend,
            Field::Residual => &self.residual,
        }
    }
}

/// The sums that make one row's statistics under a set of weights: pixels, and the sums over
/// pixels of the unbiased estimate of mu(x)^2 (P, from products of distinct batches), of the
/// weighted mean difference A and of A^2, and of the noise variance of the film's own mean
/// (see [`RowSums::add_weighted`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RowSums {
    pub n: f64,
    pub p: f64,
    pub a: f64,
    pub q: f64,
    pub v: f64,
}

/// A block's batch weights c_b w_b of [`RowSums::add_weighted`] and their sums, the same for each
/// field of the block.
pub(super) struct Weights {
    k: usize,
    cw: [f64; K],
    sum: f64,
    sum2: f64,
    c2w: f64,
    wsum: f64,
}

impl Weights {
    pub fn new(c: &[f64; K], w: &[f64; K], k: usize) -> Weights {
        let cw: [f64; K] = std::array::from_fn(|b| c[b] * w[b]);
        let (mut sum, mut sum2, mut c2w, mut wsum) = (0.0, 0.0, 0.0, 0.0);
        for b in 0..k {
            sum += cw[b];
            sum2 += cw[b] * cw[b];
            c2w += c[b] * c[b] * w[b];
            wsum += w[b];
        }
        Weights {
            k,
            cw,
            sum,
            sum2,
            c2w,
            wsum,
        }
    }
}

impl RowSums {
    /// [`RowSums::add_weighted`] with the block's weights computed here.
    #[cfg(test)]
    pub fn add(&mut self, m: &Gram, n: f64, c: &[f64; K], w: &[f64; K], k: usize, times: f64) {
        self.add_weighted(m, n, &Weights::new(c, w, k), times);
    }

    /// Adds a block of `n` pixels counted `times` times, in which batch b weighs c_b w_b
    /// ([`Weights::new`], once for every field of a block): `w` the films' batch weights (their
    /// sample counts, or equal), `c` the bootstrap's draw (at least two non-zero; all 1 for the
    /// point estimate). With those weights the pixel's mean is A = sum c_b w_b D_b / sum c_b w_b
    /// and P = sum_{b != c} (c w)_b (c w)_c D_b D_c / sum_{b != c} (c w)_b (c w)_c: the batches
    /// are independent, so E[P] = mu^2 and E[A^2 - P] = Var(A), whatever the weights. Var(A) is
    /// the noise of the replicate's weighting, not of the film's: with batch means of variance
    /// s^2 / w_b it is s^2 sum c^2 w / (sum c w)^2, so `v` gathers (A^2 - P) (sum c w)^2 /
    /// (sum c^2 w sum w), the film's own noise variance s^2 / sum w however the batches were
    /// drawn.
    pub fn add_weighted(&mut self, m: &Gram, n: f64, wt: &Weights, times: f64) {
        let (k, cw) = (wt.k, &wt.cw);
        // (G cw)_b, each summed over j in order as a row's sum would be (from -0.0, as `sum`
        // starts), but a column at a time, so that the K lanes b run side by side: G is
        // symmetric bit for bit, so column j is row j. (Row by row, each sum was a chain of
        // dependent additions, and this product most of a comparison's statistics.)
        let mut gcw = [-0.0f64; K];
        for (&x, row) in cw[..k].iter().zip(&m.g) {
            for (acc, &g) in gcw.iter_mut().zip(row) {
                *acc += x * g;
            }
        }
        let (mut cs, mut cgc, mut diag) = (0.0, 0.0, 0.0);
        for b in 0..k {
            let x = cw[b];
            cs += x * m.s[b];
            diag += x * x * m.g[b][b];
            cgc += x * gcw[b];
        }
        let (sum, sum2) = (wt.sum, wt.sum2);
        let (p, q) = ((cgc - diag) / (sum * sum - sum2), cgc / (sum * sum));
        self.n += times * n;
        self.p += times * p;
        self.a += times * cs / sum;
        self.q += times * q;
        self.v += times * (q - p) * sum * sum / (wt.c2w * wt.wsum);
    }

    /// The row's mean difference.
    pub fn mean(&self) -> f64 {
        self.a / self.n
    }

    /// Mean over the row's pixels of the noise variance of the pixel difference (of the films'
    /// own means).
    pub fn noise(&self) -> f64 {
        self.v / self.n
    }

    /// The azimuthal variance of the measured difference, noise included (the square of the
    /// paper's per-row statistic): the expected difference's variance and the noise's. For the
    /// point estimate this is the measured variance exactly; for a bootstrap replicate it is
    /// what the films' own means would measure.
    pub fn plain(&self) -> f64 {
        (self.signal() + self.noise() * (1.0 - 1.0 / self.n)).max(0.0)
    }

    /// The unbiased estimate of the azimuthal variance of the expected difference:
    /// (1/n) sum P - [(sum A)^2 - sum (A^2 - P)] / n^2. It is negative when the noise happened
    /// to exceed the signal; nothing is clipped here.
    pub fn signal(&self) -> f64 {
        let n = self.n;
        self.p / n - self.mean() * self.mean() + (self.q - self.p) / (n * n)
    }
}

/// The moments of every scenario: `[scenario][row][block]`.
pub(super) struct Table {
    pub k: usize,
    pub moments: Vec<Vec<Vec<BlockMoments>>>,
    /// Each scenario's batch weights (in proportion to the batches' sample counts when both
    /// films deal their samples alike, else equal).
    pub weights: Vec<[f64; K]>,
    pub elevations: Vec<f64>,
    pub blocks: usize,
}

/// How much each batch difference weighs: its sample count when both films split their
/// samples alike; equal weights when each film's batches hold equal counts (films of
/// different spp, each a multiple of the batch count); `None` otherwise. Any fixed weights
/// keep the estimate unbiased; these keep it efficient.
fn batch_weights(scen: &Batches, base: &Batches) -> Option<[f64; K]> {
    let uniform = |b: &Batches| b.spp.iter().all(|&c| c == b.spp[0] && c > 0);
    let mut w = [0.0; K];
    if scen.k != base.k {
        return None;
    } else if scen.spp == base.spp && scen.spp.iter().all(|&c| c > 0) {
        for (w, &c) in w.iter_mut().zip(&scen.spp) {
            *w = c as f64;
        }
    } else if uniform(scen) && uniform(base) {
        w[..scen.k].fill(1.0);
    } else {
        return None;
    }
    Some(w)
}

/// Circular moving average over `k` (odd) samples.
pub(super) fn moving_average(v: &[f64], k: usize) -> Vec<f64> {
    let n = v.len();
    let h = (k / 2) as isize;
    let at = |i: isize| v[i.rem_euclid(n as isize) as usize];
    let mut s: f64 = (-h..=h).map(at).sum();
    let mut out = Vec::with_capacity(n);
    for i in 0..n as isize {
        out.push(s / k as f64);
        s += at(i + h + 1) - at(i - h);
    }
    out
}

/// Pixels in one azimuth block of an image `w` pixels wide.
pub(super) fn block_px(w: usize) -> usize {
    ((BLOCK_DEG / 360.0 * w as f64).round() as usize).clamp(1, w)
}

pub(super) fn table(inp: &Inputs) -> Result<Table, EstimateError> {
    let base = inp.baseline;
    let bb = base.batches.as_ref().ok_or(EstimateError::NoBatches)?;
    if bb.k < 2 {
        return Err(EstimateError::TooFewSamples(base.spp));
    }
    let mut weights = Vec::new();
    for (_, f) in &inp.scenarios {
        let b = f.batches.as_ref().ok_or(EstimateError::NoBatches)?;
        if (f.image.width, f.image.height) != (base.image.width, base.image.height)
            || b.luminance.len() != bb.luminance.len()
        {
            return Err(EstimateError::Mismatch);
        }
        weights.push(batch_weights(b, bb).ok_or(EstimateError::Mismatch)?);
    }
    let (top, bottom) = inp.rows_deg;
    let w = base.image.width;
    let rows = inp.camera.rows_between((top, bottom));
    if rows.is_empty() {
        return Err(EstimateError::NoRows(top, bottom));
    }
    let k = bb.k;
    let bpx = block_px(w);
    let blocks = w.div_ceil(bpx);
    let trend_px = ((TREND_DEG / 360.0 * w as f64).round() as usize).clamp(1, w) | 1;
    let moments = inp
        .scenarios
        .par_iter()
        .map(|(_, film)| {
            let fb = film.batches.as_ref().expect("checked above");
            rows.iter()
                .map(|&y| {
                    // Per batch: the row's differences, their trend and the residual.
                    let at = |x: usize, b: usize| {
                        let i = (y * w + x) * k + b;
                        fb.luminance[i] as f64 - bb.luminance[i] as f64
                    };
                    let d: Vec<Vec<f64>> =
                        (0..k).map(|b| (0..w).map(|x| at(x, b)).collect()).collect();
                    let t: Vec<Vec<f64>> = d.iter().map(|v| moving_average(v, trend_px)).collect();
                    let mut out = vec![BlockMoments::default(); blocks];
                    let (mut dv, mut tv, mut rv) = ([0.0; K], [0.0; K], [0.0; K]);
                    for x in 0..w {
                        for b in 0..k {
                            dv[b] = d[b][x];
                            tv[b] = t[b][x];
                            rv[b] = d[b][x] - t[b][x];
                        }
                        let m = &mut out[x / bpx];
                        m.n += 1.0;
                        m.d.add(&dv, k);
                        m.trend.add(&tv, k);
                        m.residual.add(&rv, k);
                    }
                    for m in &mut out {
                        m.d.symmetrise(k);
                        m.trend.symmetrise(k);
                        m.residual.symmetrise(k);
                    }
                    out
                })
                .collect()
        })
        .collect();
    Ok(Table {
        k,
        moments,
        weights,
        elevations: rows
            .iter()
            .map(|&y| inp.camera.row_elevation_deg(y))
            .collect(),
        blocks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unequal batch weights (sample counts 1, 2, 3, 4): the unbiased pieces against their
    /// direct formulas, and the film's own noise as the batches' spread says it.
    #[test]
    fn row_sums_with_unequal_weights() {
        let k = 4;
        let w = [1.0, 2.0, 3.0, 4.0, 0.0, 0.0, 0.0, 0.0];
        let ones = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        let px: Vec<[f64; K]> = (0..5)
            .map(|i| {
                std::array::from_fn(|b| {
                    if b < k {
                        ((i * 3 + b * 5) % 7) as f64 * 0.1
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        let mut g = Gram::default();
        px.iter().for_each(|d| g.add(d, k));
        g.symmetrise(k);
        let mut r = RowSums::default();
        r.add(&g, 5.0, &ones, &w, k, 1.0);
        let wsum: f64 = w.iter().sum();
        let pairs = wsum * wsum - w.iter().map(|x| x * x).sum::<f64>();
        let (mut sp, mut sv) = (0.0, 0.0);
        for d in &px {
            let a: f64 = (0..k).map(|b| w[b] * d[b]).sum::<f64>() / wsum;
            let mut p = 0.0;
            for b in 0..k {
                for j in 0..k {
                    if b != j {
                        p += w[b] * w[j] * d[b] * d[j];
                    }
                }
            }
            sp += p / pairs;
            // Batch means of variance s^2 / w_b: s^2 from the weighted spread over k - 1, the
            // mean's variance s^2 / sum w; the unbiased (A^2 - P) form of it, rescaled.
            sv += (a * a - p / pairs) * wsum * wsum / (w.iter().sum::<f64>() * wsum);
        }
        assert!((r.p - sp).abs() < 1e-12);
        assert!((r.v - sv).abs() < 1e-12);
        // Batch means of variance s^2 / w_b (s = 1): whatever the draw, `v` estimates the
        // film's noise 1 / sum w, here 0.1, without bias.
        let mut rng = crate::rng::Rng::keyed(&[42]);
        let mut gauss = || {
            let (u1, u2) = (rng.f64().max(1e-300), rng.f64());
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        };
        let mut g = Gram::default();
        let n = 40_000;
        for _ in 0..n {
            let d: [f64; K] = std::array::from_fn(|b| {
                if b < k {
                    0.3 + gauss() / w[b].sqrt()
                } else {
                    0.0
                }
            });
            g.add(&d, k);
        }
        g.symmetrise(k);
        for c in [ones, [2.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]] {
            let mut r = RowSums::default();
            r.add(&g, n as f64, &c, &w, k, 1.0);
            assert!((r.noise() / 0.1 - 1.0).abs() < 0.03, "{c:?}: {}", r.noise());
            // No difference over the row but noise: the signal is 0 within its noise.
            assert!(r.signal().abs() < 0.005, "{c:?}: {}", r.signal());
        }
    }

    #[test]
    fn moving_average_is_circular_and_keeps_the_mean() {
        let v: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let m = moving_average(&v, 3);
        assert!((m[0] - (9.0 + 0.0 + 1.0) / 3.0).abs() < 1e-12);
        assert!((m[5] - 5.0).abs() < 1e-12);
        assert!((m.iter().sum::<f64>() - v.iter().sum::<f64>()).abs() < 1e-9);
    }

    /// The row sums against the estimator written out pixel by pixel.
    #[test]
    fn row_sums_are_the_pixelwise_unbiased_estimate() {
        let k = 4;
        let px: Vec<[f64; K]> = (0..7)
            .map(|i| {
                let mut d = [0.0; K];
                for (b, v) in d.iter_mut().enumerate().take(k) {
                    *v = ((i * 7 + b * 3) % 5) as f64 * 0.3 - 0.4 + 0.1 * b as f64;
                }
                d
            })
            .collect();
        let c = [1.0, 2.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        // Two blocks, the second counted twice.
        let (mut g1, mut g2) = (Gram::default(), Gram::default());
        px[..3].iter().for_each(|d| g1.add(d, k));
        px[3..].iter().for_each(|d| g2.add(d, k));
        g1.symmetrise(k);
        g2.symmetrise(k);
        let mut r = RowSums::default();
        let mut w = [0.0; K];
        w[..k].fill(1.0);
        r.add(&g1, 3.0, &c, &w, k, 1.0);
        r.add(&g2, 4.0, &c, &w, k, 2.0);
        // Directly.
        let pixels: Vec<&[f64; K]> = px[..3].iter().chain(&px[3..]).chain(&px[3..]).collect();
        let csum: f64 = c.iter().sum();
        let pairs = csum * csum - c.iter().map(|x| x * x).sum::<f64>();
        let (mut sp, mut sa, mut sq) = (0.0, 0.0, 0.0);
        for d in &pixels {
            let a: f64 = (0..k).map(|b| c[b] * d[b]).sum::<f64>() / csum;
            let mut p = 0.0;
            for b in 0..k {
                for j in 0..k {
                    if b != j {
                        p += c[b] * c[j] * d[b] * d[j];
                    }
                }
            }
            sp += p / pairs;
            sa += a;
            sq += a * a;
        }
        let n = pixels.len() as f64;
        assert!((r.n - n).abs() < 1e-12);
        assert!((r.p - sp).abs() < 1e-12 && (r.a - sa).abs() < 1e-12 && (r.q - sq).abs() < 1e-12);
        let want = sp / n - (sa / n).powi(2) + (sq - sp) / (n * n);
        assert!((r.signal() - want).abs() < 1e-12);
        // The noise of A under these weights, rescaled to the film's equal weights:
        // (sum c)^2 / (sum c^2 k) = 16 / 24.
        assert!((r.noise() - (sq - sp) / n * 16.0 / 24.0).abs() < 1e-12);
        // With every batch once, the variance of the measured difference.
        let mut one = RowSums::default();
        one.add(&g1, 3.0, &w, &w, k, 1.0);
        let a: Vec<f64> = px[..3]
            .iter()
            .map(|d| d[..k].iter().sum::<f64>() / k as f64)
            .collect();
        let m = a.iter().sum::<f64>() / 3.0;
        let var = a.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 3.0;
        assert!((one.plain() - var).abs() < 1e-12);
    }
}
