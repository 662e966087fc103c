//! Counter-based random numbers: every value is a hash of (seed, stream, index), so a render
//! is a pure function of its seed whatever the thread count or scheduling (DESIGN.md,
//! Determinism). The mixer is SplitMix64's finaliser (Steele, Lea & Flood 2014), which passes
//! BigCrush as a counter-mode generator.

/// SplitMix64's output function: a bijective 64-bit mixer.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// SplitMix64's step and output in one: the golden-ratio increment, then [`mix64`]. A
/// counter-mode hash of `x` (seeds, grid jitter).
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    mix64(x.wrapping_add(GOLDEN))
}

/// 2^64 / phi, SplitMix64's increment.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A small generator seeded from a hash of its keys; cheap enough to make one per sample.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A stream keyed by `keys` (e.g. `[seed, pixel, sample]`): different keys give independent
    /// streams, equal keys give the same one.
    pub fn keyed(keys: &[u64]) -> Rng {
        keys.iter().fold(Rng { state: GOLDEN }, |r, &k| r.then(k))
    }

    /// The stream keyed by this one's keys and then `key` (how [`Rng::keyed`] folds them):
    /// `Rng::keyed(&[a, b]).then(c)` is `Rng::keyed(&[a, b, c])`, so keys shared by many
    /// streams (a pixel's) are hashed once.
    /// Only for a stream that has not drawn yet (its state is still the keys' hash).
    #[inline]
    pub fn then(&self, key: u64) -> Rng {
        Rng {
            state: mix64(self.state ^ mix64(key)),
        }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(self.state)
    }

    /// Uniform in [0, 1) with 24 random bits (every value exactly representable in f32).
    #[inline]
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    #[inline]
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// A standard normal deviate (Box-Muller).
    pub fn gauss(&mut self) -> f64 {
        let (u1, u2) = (self.f64().max(1e-300), self.f64());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// A direction uniformly distributed on the unit sphere.
    pub fn unit_vector(&mut self) -> [f32; 3] {
        let z = 1.0 - 2.0 * self.f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.f32();
        [r * phi.cos(), r * phi.sin(), z]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_keyed_in_two_steps_is_the_stream_keyed_at_once() {
        let pixel = Rng::keyed(&[7, 12345]);
        for s in [0, 1, 15, u64::MAX] {
            let (mut a, mut b) = (pixel.then(s), Rng::keyed(&[7, 12345, s]));
            for _ in 0..4 {
                assert_eq!(a.next_u64(), b.next_u64());
            }
        }
        assert_ne!(pixel.then(1).next_u64(), pixel.then(2).next_u64());
    }

    #[test]
    fn keyed_streams_are_reproducible_and_distinct() {
        let a: Vec<u64> = (0..4)
            .map({
                let mut r = Rng::keyed(&[1, 2, 3]);
                move |_| r.next_u64()
            })
            .collect();
        let b: Vec<u64> = (0..4)
            .map({
                let mut r = Rng::keyed(&[1, 2, 3]);
                move |_| r.next_u64()
            })
            .collect();
        let c: Vec<u64> = (0..4)
            .map({
                let mut r = Rng::keyed(&[1, 2, 4]);
                move |_| r.next_u64()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::keyed(&[7]);
        let n = 100_000;
        let xs: Vec<f32> = (0..n).map(|_| r.f32()).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
        let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
    }
}
