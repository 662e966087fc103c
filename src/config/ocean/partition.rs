//! How the layers share the wavenumbers: each layer's raw share (a [`Bump`] in ln k) and the
//! normalized [`Partition`] of the overlapping scheme, and the band edges of both schemes.

use super::{BAND_SPLIT, LayerSpec, MIN_BAND_START_FUNDAMENTALS};

/// One layer's raw share of the wavenumbers: 0 below `lo0`, rising (smoothstep in ln k) to 1 at
/// `lo1`, 1 up to `hi1`, falling to 0 at `hi0` (an edge with equal ends is a step; the support
/// is [lo0, hi0)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    pub lo0: f64,
    pub lo1: f64,
    pub hi1: f64,
    pub hi0: f64,
}

impl Bump {
    pub fn value(&self, k: f64) -> f64 {
        if !(k >= self.lo0 && k < self.hi0) {
            return 0.0;
        }
        let ramp = |a: f64, b: f64, x: f64| {
            if x >= b {
                1.0
            } else {
                let t = ((x / a).ln() / (b / a).ln()).clamp(0.0, 1.0);
                t * t * (3.0 - 2.0 * t)
            }
        };
        let up = ramp(self.lo0, self.lo1, k);
        let down = if k <= self.hi1 {
            1.0
        } else {
            1.0 - ramp(self.hi1, self.hi0, k)
        };
        up.min(down)
    }
}

/// The layers' shares of the wavenumbers (see [`OceanParams::partition`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    pub bumps: Vec<Bump>,
}

impl Partition {
    /// Fraction of P(k) at |k| = `k` that layer `i` carries.
    pub fn weight(&self, i: usize, k: f64) -> f64 {
        let b = self.bumps[i].value(k);
        if b == 0.0 {
            return 0.0;
        }
        b / self.bumps.iter().map(|x| x.value(k)).sum::<f64>()
    }

    /// Where layer `i`'s weight can be non-zero, [lo, hi), rad/m.
    pub fn support(&self, i: usize) -> (f64, f64) {
        (self.bumps[i].lo0, self.bumps[i].hi0)
    }

    /// The |k| interval all layers together cover.
    pub fn covered(&self) -> (f64, f64) {
        let lo = self
            .bumps
            .iter()
            .map(|b| b.lo0)
            .fold(f64::INFINITY, f64::min);
        let hi = self.bumps.iter().map(|b| b.hi0).fold(0.0, f64::max);
        (lo, hi)
    }
}

/// Layer i's bump in the overlap scheme (see [`OceanParams::partition`]).
pub(super) fn overlap_bump(layers: &[LayerSpec], i: usize) -> Bump {
    let l = &layers[i];
    let fundamental = std::f64::consts::TAU / l.size_m;
    let (lo0, lo1) = if i == 0 {
        (0.5 * fundamental, 0.5 * fundamental)
    } else {
        let lo0 = MIN_BAND_START_FUNDAMENTALS * fundamental;
        (lo0, 2.0 * lo0)
    };
    let (hi1, hi0) = if i + 1 == layers.len() {
        (nyquist(l), nyquist(l))
    } else {
        let hi0 = BAND_SPLIT * nyquist(l);
        (0.5 * hi0, hi0)
    };
    Bump { lo0, lo1, hi1, hi0 }
}

pub fn nyquist(l: &LayerSpec) -> f64 {
    std::f64::consts::PI * l.n as f64 / l.size_m
}

pub fn band_edge(l: &LayerSpec) -> f64 {
    BAND_SPLIT * nyquist(l)
}
