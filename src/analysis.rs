//! Image statistics of the paper's section 5: relative luminance (Rec. 709 / sRGB primaries,
//! the paper's reference [13]) of linear RGB. The scenario comparisons build on this.

/// Relative luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of linear RGB.
#[inline]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[cfg(test)]
mod tests {
    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((super::luminance([1.0; 3]) - 1.0).abs() < 1e-6);
        assert!(super::luminance([0.0, 1.0, 0.0]) > super::luminance([1.0, 0.0, 0.0]));
    }
}
