//! Colour: relative luminance of linear RGB (Rec. 709 / sRGB primaries, the paper's reference
//! [13]), the one definition the statistics, previews and sky tools share.

/// Relative luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of linear RGB.
#[inline]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_green_dominates() {
        assert!((luminance([1.0; 3]) - 1.0).abs() < 1e-6);
        assert!(luminance([0.0, 1.0, 0.0]) > luminance([1.0, 0.0, 0.0]));
        assert!(luminance([1.0, 0.0, 0.0]) > luminance([0.0, 0.0, 1.0]));
    }
}
