//! One pixel's samples in a form that merges exactly: the count and, in fixed point, the sums
//! of the radiance, of the luminance and of its square, all integers (what a film accumulates
//! and a pass file holds).

use ethnum::U256;
use glam::Vec3;

/// Units of the fixed-point radiance sums per unit of radiance: 2^47 (radiance below about
/// 7e-15 rounds to 0). With radiances up to `crate::config::MAX_RADIANCE` (1e18 < 2^60) and at
/// most 1e6 < 2^20 samples, sums stay below 2^127 and sums of squares below 2^234.
const FIXED_ONE: f64 = (1u64 << 47) as f64;

/// `(x as f64 * FIXED_ONE).round() as i128`, bit for bit, without its two library calls on
/// baseline x86-64 (`round`, and the 128-bit conversion): below 2^53 (radiance under 64) the
/// product's integer and fractional parts are exact in f64 and i64, so rounding half away
/// from zero is a truncation and a comparison. Four of these per sample were 4 % of a render.
#[inline]
fn to_fixed(x: f32) -> i128 {
    let y = x as f64 * FIXED_ONE;
    if y.abs() < (1u64 << 53) as f64 {
        let t = y as i64;
        let frac = y - t as f64;
        (t + i64::from(frac >= 0.5) - i64::from(frac <= -0.5)) as i128
    } else {
        y.round() as i128
    }
}

/// y^2 in 256 bits. Below 2^64 (luminance under 131072) it is one 64 x 64 -> 128-bit
/// multiply; the 256-bit product, a fifth of the film's cost per sample, is kept for the rest.
#[inline]
fn square(y: u128) -> U256 {
    match u64::try_from(y) {
        Ok(y) => U256::from(u128::from(y) * u128::from(y)),
        Err(_) => U256::from(y) * U256::from(y),
    }
}

/// One pixel's samples in a form that merges exactly: the sample count and, in fixed point,
/// the sums of the radiance, of the luminance and of its square (256 bits). All are integers,
/// so any split of the samples into passes adds up to the same bits, and the variance
/// n sum(Y^2) - (sum Y)^2 is computed exactly (no cancellation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelState {
    pub sum: [i128; 3],
    pub sum_y: u128,
    pub sum_y2: U256,
    pub n: u32,
}

impl PixelState {
    /// Bytes of one state in a pass file.
    pub const BYTES: usize = 3 * 16 + 16 + 32 + 4;

    #[cfg(test)]
    pub(super) fn add(&mut self, l: Vec3) {
        self.add_with_luminance(l, crate::color::luminance(l.to_array()));
    }

    /// Adds the sample `l`, whose luminance `y` the caller has computed.
    #[inline]
    pub(super) fn add_with_luminance(&mut self, l: Vec3, y: f32) {
        for k in 0..3 {
            self.sum[k] += to_fixed(l[k]);
        }
        // Radiance is >= 0 (the guard drops anything else), so is its luminance.
        let y = to_fixed(y.max(0.0)) as u128;
        self.sum_y += y;
        self.sum_y2 += square(y);
        self.n += 1;
    }

    /// Adds another set of samples of the same pixel.
    pub fn merge(&mut self, o: &PixelState) {
        for k in 0..3 {
            self.sum[k] += o.sum[k];
        }
        self.sum_y += o.sum_y;
        self.sum_y2 += o.sum_y2;
        self.n += o.n;
    }

    /// The pixel's mean radiance.
    pub fn mean(&self) -> [f32; 3] {
        let n = self.n.max(1) as f64;
        self.sum.map(|s| (s as f64 / FIXED_ONE / n) as f32)
    }

    /// Variance of the mean luminance: s^2 / n with s^2 = (n sum(Y^2) - (sum Y)^2) / (n (n - 1)).
    pub fn var_of_mean(&self) -> f32 {
        if self.n < 2 {
            return 0.0;
        }
        let n = self.n as u128;
        let sy = U256::from(self.sum_y);
        // >= 0 exactly (Cauchy-Schwarz); saturate all the same.
        let d = (self.sum_y2 * U256::from(n)).saturating_sub(sy * sy);
        let d = d.as_f64() / (FIXED_ONE * FIXED_ONE);
        let n = n as f64;
        (d / (n * (n - 1.0)) / n) as f32
    }

    /// Little-endian bytes (pass files).
    pub fn to_bytes(&self, out: &mut Vec<u8>) {
        for s in self.sum {
            out.extend_from_slice(&s.to_le_bytes());
        }
        out.extend_from_slice(&self.sum_y.to_le_bytes());
        out.extend_from_slice(&self.sum_y2.to_le_bytes());
        out.extend_from_slice(&self.n.to_le_bytes());
    }

    /// Reads [`Self::BYTES`] bytes written by [`Self::to_bytes`].
    pub fn from_bytes(b: &[u8]) -> PixelState {
        let i = |k: usize| i128::from_le_bytes(b[16 * k..16 * k + 16].try_into().unwrap());
        PixelState {
            sum: [i(0), i(1), i(2)],
            sum_y: u128::from_le_bytes(b[48..64].try_into().unwrap()),
            sum_y2: U256::from_le_bytes(b[64..96].try_into().unwrap()),
            n: u32::from_le_bytes(b[96..100].try_into().unwrap()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rounded(x: f32) -> i128 {
        (x as f64 * FIXED_ONE).round() as i128
    }

    #[test]
    fn fixed_point_conversion_is_rounding_bit_for_bit() {
        let tie = (0.5 / FIXED_ONE) as f32; // 2^-48: exactly half a unit
        for x in [
            0.0f32,
            -0.0,
            tie,
            -tie,
            3.0 * tie,
            -3.0 * tie,
            1.0,
            0.1,
            63.99,
            64.0,
            64.5,
            1e6,
            1e18,
            -1e18,
            f32::MAX,
            f32::NAN,
            f32::INFINITY,
            f32::MIN_POSITIVE,
            1e-30,
        ] {
            assert_eq!(to_fixed(x), rounded(x), "{x:e}");
        }
    }

    #[test]
    fn fixed_point_conversion_matches_rounding_across_the_floats() {
        // a million bit patterns spread over every exponent and sign, and each exponent's
        // first, middle and last significands (the fast path's edge at 2^53, ties among them)
        let spread = (0..=u32::MAX).step_by(4099);
        let edges = (0..512u32)
            .flat_map(|se| [0, 1, 0x40_0000, 0x40_0001, 0x7f_ffff].map(|m| se << 23 | m));
        for bits in spread.chain(edges) {
            let x = f32::from_bits(bits);
            assert_eq!(to_fixed(x), rounded(x), "{x:e} ({bits:#x})");
        }
    }

    #[test]
    fn squares_are_exact_on_both_sides_of_the_fast_path() {
        let edge = u128::from(u64::MAX);
        for y in [
            0,
            1,
            3,
            1 << 47,
            edge - 1,
            edge,
            edge + 1,
            1 << 100,
            u128::MAX,
        ] {
            assert_eq!(square(y), U256::from(y) * U256::from(y), "{y}");
        }
    }

    proptest::proptest! {
        #[test]
        fn fixed_point_conversion_matches_rounding_on_any_float(bits in proptest::prelude::any::<u32>()) {
            let x = f32::from_bits(bits);
            proptest::prop_assert_eq!(to_fixed(x), rounded(x));
        }
    }
}
