//! The numbers of each camera sample that its pixel's samples share out between them: where
//! in the pixel the ray starts, and the two numbers its first rough hit draws its normal
//! from the unresolved waves' lobe with. A pixel's samples are dealt into independent batches
//! (`super::film`), and within a batch its samples take consecutive points of one
//! four-dimensional Sobol' sequence, each dimension Owen-scrambled with the batch's own seed
//! (Burley 2020, "Practical Hash-based Owen Scrambling"; pbrt-v4's `FastOwenScrambler`). So
//! each point alone is uniform, the batches stay independent renders of the pixel (the error
//! estimator's batch means keep their meaning), and the 2^m samples of a batch are
//! stratified together over the pixel and the lobe: along each of the four axes one point in
//! each 2^-m of it, and the lobe's pair (the first two dimensions, a (0,2)-sequence) one
//! point in every elementary interval of area 2^-m. Stratified together rather than each pair
//! apart, because the light a rough hit sends to the camera depends on the sum of the
//! resolved slope (where in the pixel) and the drawn one: paired at random with the pixel's
//! positions, the stratified draw took 1.07x off the band's noise at 128 samples, against
//! 1.18x together (docs/filtered.md, "Samples stratified over the pixel and the lobe").

use crate::rng::mix64;

/// The scrambling seeds of one batch of one pixel, one per dimension.
#[derive(Clone, Copy, Debug)]
pub struct Strata {
    dims: [u32; 4],
}

/// Joe & Kuo's direction numbers (new-joe-kuo-6.21201) for Sobol's third and fourth
/// dimensions: primitive polynomials x^2 + x + 1 and x^3 + x + 1, initial numbers 1, 3 and
/// 1, 3, 1.
const THIRD: [u32; 32] = directions(2, 1, [1, 3, 0]);
const FOURTH: [u32; 32] = directions(3, 1, [1, 3, 1]);
/// The second dimension's: the rows of Pascal's triangle modulo 2 (polynomial x + 1).
const SECOND: [u32; 32] = directions(1, 0, [1, 0, 0]);

/// Each point is built with its bits reversed, where the scramble works (see
/// [`owen_scramble_reversed`]): the direction numbers of the second to fourth dimensions
/// reversed (the first dimension's reversed point is the index itself).
const REVERSED: [[u32; 32]; 3] = [reversed(SECOND), reversed(THIRD), reversed(FOURTH)];

const fn reversed(v: [u32; 32]) -> [u32; 32] {
    let mut r = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        r[k] = v[k].reverse_bits();
        k += 1;
    }
    r
}

/// The 32 direction numbers of a Sobol' dimension from its polynomial's degree `s`, its inner
/// coefficients `a` (s - 1 bits, the highest first) and its `s` initial numbers `m`.
const fn directions(s: usize, a: u32, m: [u32; 3]) -> [u32; 32] {
    let mut mk = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        mk[k] = if k < s {
            m[k]
        } else {
            let mut v = mk[k - s] ^ (mk[k - s] << s);
            let mut i = 1;
            while i < s {
                if (a >> (s - 1 - i)) & 1 == 1 {
                    v ^= mk[k - i] << i;
                }
                i += 1;
            }
            v
        };
        k += 1;
    }
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        v[k] = mk[k] << (31 - k);
        k += 1;
    }
    v
}

/// Point `i` of the Sobol' dimension of direction numbers `v`.
fn sobol(v: &[u32; 32], mut i: u32) -> u32 {
    let (mut r, mut k) = (0u32, 0);
    while i != 0 {
        if i & 1 != 0 {
            r ^= v[k];
        }
        i >>= 1;
        k += 1;
    }
    r
}

impl Strata {
    /// The seeds hashed from a 64-bit key (a pixel's and batch's).
    pub fn new(key: u64) -> Strata {
        let a = mix64(key);
        let b = mix64(a ^ 0x5851_f42d_4c95_7f2d);
        Strata {
            dims: [a as u32, (a >> 32) as u32, b as u32, (b >> 32) as u32],
        }
    }

    /// Point `index` of the batch's sequence: the lobe's two numbers, then the position in
    /// the pixel across and down, each in [0, 1) with 24 bits (exactly representable in f32).
    /// (The index is not shuffled as pbrt-v4's padded sampler shuffles it to decorrelate
    /// separate pairs: these four dimensions are meant together, and an index of a few bits
    /// keeps the direction numbers' loops short; a shuffled 32-bit one made this 30 % of a
    /// render.)
    pub fn point(&self, index: u32) -> [f32; 4] {
        let rev = [
            index,
            sobol(&REVERSED[0], index),
            sobol(&REVERSED[1], index),
            sobol(&REVERSED[2], index),
        ];
        std::array::from_fn(|d| unit(owen_scramble_reversed(rev[d], self.dims[d]).reverse_bits()))
    }
}

/// A nested uniform (Owen) scramble of the bits of a number, most significant first (each
/// bit flipped or not by a hash of the bits above it), done on its bits reversed `v`, where a
/// multiply carries from the lower bits to the higher ones only: pbrt-v4's
/// `FastOwenScrambler` without its two reversals. Returns the scrambled number's bits
/// reversed.
fn owen_scramble_reversed(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v
}

/// The top 24 bits as a number in [0, 1).
fn unit(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which of the 2^m cells of an elementary interval [a 2^-p, (a + 1) 2^-p) x [b 2^-q, (b +
    /// 1) 2^-q), p + q = m, the point (x, y) lies in.
    fn cell(x: f32, y: f32, p: u32, q: u32) -> usize {
        let (a, b) = ((x * (1 << p) as f32) as u32, (y * (1 << q) as f32) as u32);
        (a << q | b) as usize
    }

    /// The first 2^m points of a batch (m up to 8), and every aligned block of 2^m consecutive
    /// points (a batch boosted past 2^m samples): the lobe's pair holds one point in every
    /// elementary interval of area 2^-m, and each of the four dimensions one point in each
    /// 2^-m of its axis. Fails with a direction number wrong or a scramble that is not
    /// nested (a bit flipped by a hash of the bits below it).
    #[test]
    fn each_block_of_a_batch_is_stratified() {
        for key in 0..40u64 {
            let s = Strata::new(key);
            for m in 1..=8u32 {
                let n = 1u32 << m;
                for block in [0, 1, 5] {
                    let points: Vec<[f32; 4]> = (0..n).map(|j| s.point(block * n + j)).collect();
                    for p in 0..=m {
                        let mut seen = vec![false; n as usize];
                        for pt in &points {
                            let c = cell(pt[0], pt[1], p, m - p);
                            assert!(!seen[c], "key {key} m {m} block {block} p {p}");
                            seen[c] = true;
                        }
                    }
                    for d in 0..4 {
                        let mut seen = vec![false; n as usize];
                        for pt in &points {
                            let c = cell(pt[d], 0.0, m, 0);
                            assert!(!seen[c], "key {key} m {m} block {block} dimension {d}");
                            seen[c] = true;
                        }
                    }
                }
            }
        }
    }

    /// The second to fourth dimensions are Sobol's: its first eight points in index order
    /// (what a Gray-code generator, as SciPy's, lists as its points 0, 1, 3, 2, 7, 6, 4, 5).
    #[test]
    fn direction_numbers_give_sobols_points() {
        let unit = |v: u32| v as f64 / 2f64.powi(32);
        let second: Vec<f64> = (0..8).map(|i| unit(sobol(&SECOND, i))).collect();
        let third: Vec<f64> = (0..8).map(|i| unit(sobol(&THIRD, i))).collect();
        let fourth: Vec<f64> = (0..8).map(|i| unit(sobol(&FOURTH, i))).collect();
        assert_eq!(second, [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875]);
        assert_eq!(third, [0.0, 0.5, 0.75, 0.25, 0.375, 0.875, 0.625, 0.125]);
        assert_eq!(fourth, [0.0, 0.5, 0.75, 0.25, 0.125, 0.625, 0.875, 0.375]);
    }

    /// Over the batches' seeds each point is uniform: the histogram of each coordinate of
    /// point j over 20,000 seeds against the uniform one (a chi-square with 15 degrees of
    /// freedom below its 0.9999 quantile, 44.6), for the first points of a batch and a later
    /// one; and no two coordinates are correlated.
    #[test]
    fn every_point_is_uniform_over_the_seeds() {
        const SEEDS: u64 = 20_000;
        const BINS: usize = 16;
        for j in [0u32, 1, 2, 3, 7, 100] {
            let mut hist = [[0u32; BINS]; 4];
            let mut cross = [[0.0f64; 4]; 4];
            for key in 0..SEEDS {
                let pt = Strata::new(key.wrapping_mul(0x9e37_79b9_7f4a_7c15)).point(j);
                for (d, &x) in pt.iter().enumerate() {
                    assert!((0.0..1.0).contains(&x));
                    hist[d][(x * BINS as f32) as usize] += 1;
                    for e in 0..d {
                        cross[d][e] += (x as f64 - 0.5) * (pt[e] as f64 - 0.5);
                    }
                }
            }
            let expected = SEEDS as f64 / BINS as f64;
            for h in hist {
                let chi2: f64 = h
                    .iter()
                    .map(|&c| (c as f64 - expected).powi(2) / expected)
                    .sum();
                assert!(chi2 < 44.6, "point {j}: chi-square {chi2} {h:?}");
            }
            // a correlation's standard error is 1/sqrt(SEEDS): 0.007
            for (d, row) in cross.iter().enumerate() {
                for &c in &row[..d] {
                    let corr = c / SEEDS as f64 * 12.0;
                    assert!(corr.abs() < 0.035, "point {j}: correlation {corr}");
                }
            }
        }
    }

    /// Two batches of one pixel (different seeds) are not the same points.
    #[test]
    fn batches_differ() {
        let (a, b) = (Strata::new(1), Strata::new(2));
        assert!((0..4).all(|j| a.point(j) != b.point(j)));
    }
}
