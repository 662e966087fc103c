//! One swell partition of a sea state's spectrum (`Spectrum::swells`): its JONSWAP level, peak
//! and direction, and its cos-2s spreading with the normalisation computed once.

use std::f64::consts::{PI, TAU};

use super::{ln_gamma, wrap_angle};
use crate::ocean::SwellParams;

/// One swell partition: JONSWAP S(omega) (times the depth factor under TMA) with its own level,
/// peak and enhancement, spread by cos-2s of a fixed exponent around its direction.
#[derive(Clone, Debug)]
pub struct SwellSpectrum {
    /// Energy level of its JONSWAP, scaled so the partition holds its asked share (see
    /// [`Spectrum::new`]).
    pub alpha: f64,
    pub omega_p: f64,
    pub gamma: f64,
    /// Direction it travels towards, radians from +x towards +z.
    pub dir_rad: f64,
    /// cos-2s exponent.
    pub s: f64,
    /// ln of cos-2s's normalisation Q(s), computed once.
    ln_q: f64,
    /// The significant wave height asked for, m.
    pub hs_m: f64,
}

impl SwellSpectrum {
    pub(super) fn new(p: &SwellParams) -> SwellSpectrum {
        let s = p.spreading_s;
        SwellSpectrum {
            alpha: 1.0,
            omega_p: TAU / p.tp_s,
            gamma: p.gamma,
            dir_rad: p.dir_deg.to_radians(),
            s,
            ln_q: (2.0 * s - 1.0) * 2f64.ln() - PI.ln() + 2.0 * ln_gamma(s + 1.0)
                - ln_gamma(2.0 * s + 1.0),
            hs_m: p.hs_m,
        }
    }

    /// Its cos-2s spreading at wave direction `theta_k` (radians from +x towards +z).
    pub(super) fn spreading_at(&self, theta_k: f64) -> f64 {
        let c = (0.5 * wrap_angle(theta_k - self.dir_rad)).cos().abs();
        if c == 0.0 {
            return 0.0;
        }
        (self.ln_q + 2.0 * self.s * c.ln()).exp()
    }
}
