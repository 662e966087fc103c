//! The bootstrap of the Monte Carlo noise: each replicate redraws, independently in every
//! azimuth block, which of the block's batches it takes (k draws with replacement from the k
//! batches). The batches of a block are k independent renders of its pixels and blocks hold
//! disjoint pixels, so this resamples exactly the randomness the estimate has: the samples.
//! The image itself (its waves, its sky, where the sun glints) is held fixed, because the
//! estimate is of this image's converged value (see the module doc of [`super`] for why and
//! for the alternative of also redrawing blocks, measured and not kept).

use super::moments::K;
use crate::rng::Rng;

/// Bootstrap replicates.
pub const REPLICATES: usize = 1000;

/// The weights of one replicate: per block, each batch's count among the k draws.
pub(super) type Draw = Vec<[f64; K]>;

/// The weights of the point estimate: every batch once in every block.
pub(super) fn identity(blocks: usize, k: usize) -> Draw {
    let mut c = [0.0; K];
    c[..k].fill(1.0);
    vec![c; blocks]
}

/// Replicate `r`'s draw, deterministic in `seed`. A block whose draw holds a single distinct
/// batch (probability k^(1-k), 2e-6 for k = 8) is drawn again: the estimate needs two.
pub(super) fn draw(seed: u64, r: usize, blocks: usize, k: usize) -> Draw {
    (0..blocks)
        .map(|g| {
            let mut rng = Rng::keyed(&[seed, 0x626f_6f74, r as u64, g as u64]);
            loop {
                let mut c = [0.0; K];
                for _ in 0..k {
                    c[((rng.f64() * k as f64) as usize).min(k - 1)] += 1.0;
                }
                if c.iter().filter(|&&x| x > 0.0).count() >= 2 {
                    break c;
                }
            }
        })
        .collect()
}

/// How much a replicate's distance from the estimate is scaled before the interval is read:
/// a bootstrap of k independent values sees (k - 1) / k of their variance, so the distances
/// are scaled by sqrt(k / (k - 1)) (1.07 for k = 8).
pub(super) fn inflation(k: usize) -> f64 {
    (k as f64 / (k as f64 - 1.0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_deterministic_multinomial_and_never_degenerate() {
        let (blocks, k) = (500, 8);
        let a = draw(7, 3, blocks, k);
        assert_eq!(a, draw(7, 3, blocks, k));
        assert_ne!(a, draw(7, 4, blocks, k));
        let mut per_batch = [0.0; K];
        for c in &a {
            assert_eq!(c.iter().sum::<f64>(), k as f64);
            assert!(c.iter().filter(|&&x| x > 0.0).count() >= 2);
            for b in 0..k {
                per_batch[b] += c[b];
            }
        }
        // Each batch drawn about blocks times (Poisson-like spread: sd ~ 21).
        for &n in &per_batch[..k] {
            assert!((n - blocks as f64).abs() < 100.0, "{per_batch:?}");
        }
        // Two batches: never one alone.
        assert!(
            draw(1, 0, 1000, 2)
                .iter()
                .all(|c| c[0] == 1.0 && c[1] == 1.0)
        );
    }
}
