//! Sea-state spectra and the wavevector spectrum P(k) whose random realization is h0(k) of
//! paper eq. 2. Frequency spectra S(omega): JONSWAP with fetch-limited parameters
//! (Hasselmann et al. 1973: alpha = 0.076 (U^2/(F g))^0.22, omega_p = 22 (g^2/(U F))^(1/3),
//! sigma 0.07/0.09), TMA = JONSWAP x Kitaigorodskii's depth factor (Bouws et al. 1985, the
//! spectrum of the paper's Table 1), Pierson-Moskowitz and Phillips (Tessendorf's, rewritten in
//! omega). Spreading D(theta; omega): Mitsuyasu cos-2s and Donelan-Banner sech^2 (as collected by
//! Horvath 2015), cos^2 and uniform. Finite-depth dispersion omega^2 = g k tanh(k h), and
//! P(k) = S(omega(k)) D(theta) (d omega / d k) / k, so that the integral of P over the plane is
//! the integral of S over omega (Massel 1996, ch. 3).

use std::f64::consts::{PI, TAU};

use super::{OceanParams, SpectrumKind, SpreadingKind};

#[path = "spectrum_swell.rs"]
mod swell;
pub use swell::SwellSpectrum;
#[path = "spectrum_table.rs"]
mod table;
pub use table::RadialTable;

/// Standard gravity, m/s^2.
pub const G: f64 = 9.81;

/// Phillips' saturation constant, used by the Pierson-Moskowitz and Phillips spectra.
pub const PHILLIPS_ALPHA: f64 = 0.0081;

/// Angular frequency of a wave of wavenumber `k` on water `depth` deep: omega^2 = g k tanh(k h).
pub fn dispersion(k: f64, depth: f64) -> f64 {
    (G * k * (k * depth).tanh()).sqrt()
}

/// d omega / d k of [`dispersion`] (the group velocity).
pub fn group_velocity(k: f64, depth: f64) -> f64 {
    let kh = k * depth;
    let t = kh.tanh();
    let w = (G * k * t).sqrt();
    if w == 0.0 {
        // k -> 0: omega ~ k sqrt(g h)
        return (G * depth).sqrt();
    }
    G * (t + kh * (1.0 - t * t)) / (2.0 * w)
}

/// Inverse of [`dispersion`]: the wavenumber with angular frequency `omega`.
pub fn wavenumber(omega: f64, depth: f64) -> f64 {
    if omega <= 0.0 {
        return 0.0;
    }
    // tanh x <= min(x, 1) and tanh x >= tanh(1) min(x, 1) bracket the root.
    let t1 = 1f64.tanh();
    let mut lo = (omega * omega / G).max(omega / (G * depth).sqrt());
    let mut hi = (omega * omega / (G * t1)).max(omega / (G * depth * t1).sqrt());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if dispersion(mid, depth) < omega {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// Kitaigorodskii's depth factor Phi(omega_h), omega_h = omega sqrt(h/g) (Bouws et al. 1985).
pub fn kitaigorodskii(omega_h: f64) -> f64 {
    if omega_h <= 1.0 {
        0.5 * omega_h * omega_h
    } else if omega_h < 2.0 {
        1.0 - 0.5 * (2.0 - omega_h) * (2.0 - omega_h)
    } else {
        1.0
    }
}

/// JONSWAP (alpha, omega_p) for wind speed `u` (m/s) over fetch `fetch_m` (m).
pub fn jonswap_parameters(u: f64, fetch_m: f64) -> (f64, f64) {
    let alpha = 0.076 * (u * u / (fetch_m * G)).powf(0.22);
    let omega_p = 22.0 * (G * G / (u * fetch_m)).cbrt();
    (alpha, omega_p)
}

/// JONSWAP S(omega), m^2 s.
pub fn jonswap(omega: f64, alpha: f64, omega_p: f64, gamma: f64) -> f64 {
    if omega <= 0.0 {
        return 0.0;
    }
    let sigma = if omega <= omega_p { 0.07 } else { 0.09 };
    let d = (omega - omega_p) / (sigma * omega_p);
    let r = (-0.5 * d * d).exp();
    pierson_moskowitz_shape(omega, alpha, omega_p) * gamma.powf(r)
}

/// alpha g^2 omega^-5 exp(-5/4 (omega_p/omega)^4): Pierson-Moskowitz, JONSWAP without the peak.
pub fn pierson_moskowitz_shape(omega: f64, alpha: f64, omega_p: f64) -> f64 {
    if omega <= 0.0 {
        return 0.0;
    }
    let q = omega_p / omega;
    let q4 = (q * q) * (q * q);
    alpha * G * G / omega.powi(5) * (-1.25 * q4).exp()
}

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9; ~1e-15 relative).
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // reflection keeps the series in its accurate range
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * TAU.ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// cos-2s spreading Q(s) |cos(theta/2)|^(2s), normalised over [-pi, pi].
pub fn cos_2s(theta: f64, s: f64) -> f64 {
    let ln_q =
        (2.0 * s - 1.0) * 2f64.ln() - PI.ln() + 2.0 * ln_gamma(s + 1.0) - ln_gamma(2.0 * s + 1.0);
    let c = (0.5 * theta).cos().abs();
    if c == 0.0 {
        return if s == 0.0 { ln_q.exp() } else { 0.0 };
    }
    (ln_q + 2.0 * s * c.ln()).exp()
}

/// g F / U^2 beyond which a sea is fully developed: JONSWAP's omega_p = 22 (g^2 / (U F))^(1/3)
/// meets Pierson-Moskowitz's 0.855 g / U at (22 / 0.855)^3.
pub const FULLY_DEVELOPED_FETCH: f64 = 17_035.0;

/// The largest spreading exponent at the peak the warnings accept (Goda 1985: s_max = 10 for
/// wind waves, 25 for swell with short decay distance, 75 for swell with long decay distance).
pub const MAX_PEAK_SPREADING: f64 = 75.0;

/// Mitsuyasu's exponent s(omega) (Mitsuyasu et al. 1975, as in Horvath 2015 eq. 33-34).
pub fn mitsuyasu_s(omega: f64, omega_p: f64, u: f64) -> f64 {
    mitsuyasu_s_from_peak(omega, omega_p, mitsuyasu_peak(omega_p, u))
}

/// Mitsuyasu's exponent at the peak, s_p = 11.5 (g / (omega_p U))^2.5.
fn mitsuyasu_peak(omega_p: f64, u: f64) -> f64 {
    11.5 * (G / (omega_p * u)).powf(2.5)
}

/// [`mitsuyasu_s`] from the exponent at the peak `s_p` (what a spectrum computes once).
fn mitsuyasu_s_from_peak(omega: f64, omega_p: f64, s_p: f64) -> f64 {
    let r = omega / omega_p;
    if r <= 1.0 {
        s_p * r.powi(5)
    } else {
        s_p * r.powf(-2.5)
    }
}

/// Donelan-Banner beta(omega / omega_p).
pub fn donelan_banner_beta(r: f64) -> f64 {
    if r < 0.95 {
        2.61 * r.powf(1.3)
    } else if r < 1.6 {
        2.28 * r.powf(-1.3)
    } else {
        10f64.powf(-0.4 + 0.8393 * (-0.567 * (r * r).ln()).exp())
    }
}

/// Donelan-Banner spreading beta / (2 tanh(beta pi)) sech^2(beta theta), normalised over [-pi, pi].
pub fn donelan_banner(theta: f64, beta: f64) -> f64 {
    if beta < 1e-9 {
        return 1.0 / TAU;
    }
    let sech = 1.0 / (beta * theta).cosh();
    beta / (2.0 * (beta * PI).tanh()) * sech * sech
}

/// Wraps an angle into [-pi, pi).
fn wrap_angle(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

/// Which partition of a sea state: the wind sea or swell i.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Wind,
    Swell(usize),
}

/// A sea state: S(omega), D(theta; omega) and the dispersion relation, ready to give P(k).
/// The wind sea and any swells add up (linear waves superpose).
#[derive(Clone, Debug)]
pub struct Spectrum {
    pub kind: SpectrumKind,
    pub spreading: SpreadingKind,
    pub wind_speed: f64,
    pub fetch_m: f64,
    pub depth_m: f64,
    pub gamma: f64,
    /// Direction the wind blows towards, radians from +x towards +z.
    pub wind_dir_rad: f64,
    /// Energy level of S (alpha of JONSWAP / PM / Phillips).
    pub alpha: f64,
    /// Peak angular frequency of S(omega), rad/s.
    pub omega_p: f64,
    /// Frequency that sets the low-frequency cut-off exp(-c (omega_c/omega)^4).
    omega_cut: f64,
    /// Largest Mitsuyasu exponent (`OceanParams::spreading_cap`); infinity = uncapped.
    pub spreading_cap: f64,
    /// Mitsuyasu's exponent at the peak as published, computed once (every cell of every
    /// layer needs it twice).
    mitsuyasu_peak: f64,
    /// Whether the peak comes from the fetch law (not from `tp_s`).
    fetch_law: bool,
    pub swells: Vec<SwellSpectrum>,
}

impl Spectrum {
    /// The spectrum of `params` (which should have been validated).
    pub fn new(params: &OceanParams) -> Spectrum {
        let u = params.wind_speed;
        let fetch_m = params.fetch_km * 1000.0;
        let mut spectrum;
        let (alpha, omega_p, omega_cut) = match params.spectrum {
            SpectrumKind::Tma | SpectrumKind::Jonswap => {
                let (a, wp) = jonswap_parameters(u, fetch_m);
                let wp = params.tp_s.map_or(wp, |tp| TAU / tp);
                (a, wp, wp)
            }
            // omega_p = 0.855 g / U10 (Horvath 2015 eq. 21)
            SpectrumKind::PiersonMoskowitz => (PHILLIPS_ALPHA, 0.855 * G / u, 0.855 * G / u),
            // exp(-1/(k L)^2) with L = U^2/g is exp(-(g/(U omega))^4) in deep water; the peak of
            // omega^-5 exp(-(w0/omega)^4) is at (4/5)^(1/4) w0.
            SpectrumKind::Phillips => (PHILLIPS_ALPHA, 0.8f64.powf(0.25) * G / u, G / u),
        };
        spectrum = Spectrum {
            kind: params.spectrum,
            spreading: params.spreading,
            wind_speed: u,
            fetch_m,
            depth_m: params.depth_m,
            gamma: params.gamma,
            wind_dir_rad: params.wind_dir_deg.to_radians(),
            alpha,
            omega_p,
            omega_cut,
            spreading_cap: params.spreading_cap.unwrap_or(f64::INFINITY),
            mitsuyasu_peak: mitsuyasu_peak(omega_p, u),
            fetch_law: params.tp_s.is_none(),
            swells: Vec::new(),
        };
        spectrum.add_swells(params);
        spectrum
    }

    /// Adds the swells of `params`, each at the level that gives it its asked Hs over the
    /// wavenumbers the layers resolve, relative to the wind sea: with a wind-sea target the
    /// swells' levels are set so the partitions' variances stand as the targets do (the
    /// realization is then scaled to the total), without one each swell holds its Hs outright.
    fn add_swells(&mut self, params: &OceanParams) {
        if params.swell.is_empty() {
            return;
        }
        let (k_lo, k_hi) = match (params.layers.first(), params.layers.last()) {
            (Some(first), Some(last)) => (PI / first.size_m, super::nyquist(last)),
            _ => (0.0, f64::INFINITY),
        };
        self.swells = params.swell.iter().map(SwellSpectrum::new).collect();
        let wind = self.part_variance(Part::Wind, k_lo, k_hi, |_| 1.0);
        let relative = match params.wind_rms_target() {
            Some(t) if wind > 0.0 => wind / (t * t),
            _ => 1.0,
        };
        for i in 0..self.swells.len() {
            let unit = self.part_variance(Part::Swell(i), k_lo, k_hi, |_| 1.0);
            let asked = (self.swells[i].hs_m / 4.0).powi(2);
            self.swells[i].alpha = if unit > 0.0 {
                asked / unit * relative
            } else {
                0.0
            };
        }
    }

    /// The dimensionless fetch g F / U^2 (TMA and JONSWAP; `None` for the others).
    pub fn dimensionless_fetch(&self) -> Option<f64> {
        (self.fetch_law && matches!(self.kind, SpectrumKind::Tma | SpectrumKind::Jonswap))
            .then(|| G * self.fetch_m / (self.wind_speed * self.wind_speed))
    }

    /// Mitsuyasu's spreading exponent at the spectral peak as published (`None` for other
    /// spreadings); the surface uses it capped at `spreading_cap`.
    pub fn peak_spreading_exponent(&self) -> Option<f64> {
        (self.spreading == SpreadingKind::Mitsuyasu)
            .then(|| mitsuyasu_s(self.omega_p, self.omega_p, self.wind_speed))
    }

    /// Where the inputs leave the range the spectrum's models were fitted on, as short clauses
    /// for one note: a fetch past full development (g F / U^2 > [`FULLY_DEVELOPED_FETCH`], where
    /// the JONSWAP peak falls below Pierson-Moskowitz's 0.855 g / U) and a spreading exponent at
    /// the peak above [`MAX_PEAK_SPREADING`] (Goda's largest, for long-travelled swell; wind seas
    /// are near 10). The surface is still valid there: the models extrapolate.
    pub fn range_notes(&self) -> Vec<String> {
        let mut w = Vec::new();
        // (a preset's fully developed sea sits at the bound itself, give or take rounding)
        if let Some(f) = self.dimensionless_fetch()
            && f > FULLY_DEVELOPED_FETCH * (1.0 + 1e-9)
        {
            w.push(format!(
                "the fetch is past full development (g F / U^2 = {f:.3e} > {FULLY_DEVELOPED_FETCH:.3e}), so JONSWAP's fetch law puts the peak at omega_p U / g = {:.2}, below the fully developed 0.855",
                self.omega_p * self.wind_speed / G
            ));
        }
        if let Some(s) = self.peak_spreading_exponent()
            && s.min(self.spreading_cap) > MAX_PEAK_SPREADING
        {
            w.push(format!(
                "the waves are nearly long-crested (Mitsuyasu's spreading exponent at the peak is {s:.0}, above Goda's {MAX_PEAK_SPREADING:.0} for long-travelled swell; --spreading-cap {MAX_PEAK_SPREADING:.0} caps it)"
            ));
        }
        w
    }

    /// Frequency spectrum S(omega) of the whole sea, m^2 s: the variance is its integral over
    /// omega > 0.
    pub fn s_omega(&self, omega: f64) -> f64 {
        let wind = self.wind_s_omega(omega);
        if self.swells.is_empty() {
            return wind;
        }
        wind + (0..self.swells.len())
            .map(|i| self.swell_s_omega(i, omega))
            .sum::<f64>()
    }

    /// S(omega) of one partition.
    pub fn part_s_omega(&self, part: Part, omega: f64) -> f64 {
        match part {
            Part::Wind => self.wind_s_omega(omega),
            Part::Swell(i) => self.swell_s_omega(i, omega),
        }
    }

    fn swell_s_omega(&self, i: usize, omega: f64) -> f64 {
        let sw = &self.swells[i];
        let s = jonswap(omega, sw.alpha, sw.omega_p, sw.gamma);
        if self.kind == SpectrumKind::Tma {
            s * kitaigorodskii(omega * (self.depth_m / G).sqrt())
        } else {
            s
        }
    }

    fn wind_s_omega(&self, omega: f64) -> f64 {
        match self.kind {
            SpectrumKind::Jonswap => jonswap(omega, self.alpha, self.omega_p, self.gamma),
            SpectrumKind::Tma => {
                let wh = omega * (self.depth_m / G).sqrt();
                jonswap(omega, self.alpha, self.omega_p, self.gamma) * kitaigorodskii(wh)
            }
            SpectrumKind::PiersonMoskowitz => {
                pierson_moskowitz_shape(omega, self.alpha, self.omega_p)
            }
            SpectrumKind::Phillips => {
                if omega <= 0.0 {
                    return 0.0;
                }
                let q = self.omega_cut / omega;
                self.alpha * G * G / omega.powi(5) * (-(q * q) * (q * q)).exp()
            }
        }
    }

    /// Angular width of D(theta; omega), radians: the standard deviation of the narrow-spread
    /// limit (cos^2s ~ exp(-s theta^2 / 4): sqrt(2 / s); sech^2(beta theta): pi / (2 sqrt(3) beta)),
    /// for choosing how finely a grid cell must be integrated.
    pub fn spreading_width(&self, omega: f64) -> f64 {
        // a swell's cos-2s is as narrow at every frequency
        let swell = self
            .swells
            .iter()
            .map(|s| (2.0 / s.s).sqrt().min(PI))
            .fold(PI, f64::min);
        swell.min(self.wind_spreading_width(omega))
    }

    fn wind_spreading_width(&self, omega: f64) -> f64 {
        match self.spreading {
            SpreadingKind::Mitsuyasu => {
                let s = mitsuyasu_s_from_peak(omega, self.omega_p, self.mitsuyasu_peak)
                    .min(self.spreading_cap);
                (2.0 / s.max(1e-9)).sqrt().min(PI)
            }
            SpreadingKind::DonelanBanner => {
                let beta = donelan_banner_beta(omega / self.omega_p);
                (PI / (2.0 * 3f64.sqrt() * beta.max(1e-9))).min(PI)
            }
            SpreadingKind::Cos2 => 0.5,
            SpreadingKind::Uniform => PI,
        }
    }

    /// Directional spreading D(theta; omega), theta measured from the downwind direction.
    pub fn spreading_at(&self, omega: f64, theta: f64) -> f64 {
        match self.spreading {
            SpreadingKind::Mitsuyasu => {
                let s = mitsuyasu_s_from_peak(omega, self.omega_p, self.mitsuyasu_peak);
                cos_2s(theta, s.min(self.spreading_cap))
            }
            SpreadingKind::DonelanBanner => {
                donelan_banner(theta, donelan_banner_beta(omega / self.omega_p))
            }
            SpreadingKind::Cos2 => {
                let c = theta.cos();
                if c > 0.0 { 2.0 / PI * c * c } else { 0.0 }
            }
            SpreadingKind::Uniform => 1.0 / TAU,
        }
    }

    /// omega(k) with this sea's depth.
    pub fn omega(&self, k: f64) -> f64 {
        dispersion(k, self.depth_m)
    }

    /// Wavevector spectrum P(k), m^4: P = S(omega) D(theta) (d omega/d k) / k.
    pub fn p_k(&self, kx: f64, kz: f64) -> f64 {
        let k = kx.hypot(kz);
        if k == 0.0 {
            return 0.0;
        }
        self.p_k_at(kx, kz, k, self.omega(k))
    }

    /// [`Spectrum::p_k`] where |k| = `k` > 0 and `omega` = omega(k) are already known.
    pub(crate) fn p_k_at(&self, kx: f64, kz: f64, k: f64, omega: f64) -> f64 {
        let theta_k = kz.atan2(kx);
        let s = self.wind_s_omega(omega);
        let mut p = 0.0;
        if s != 0.0 {
            p = s * self.spreading_at(omega, wrap_angle(theta_k - self.wind_dir_rad));
        }
        for (i, sw) in self.swells.iter().enumerate() {
            let s = self.swell_s_omega(i, omega);
            if s != 0.0 {
                p += s * sw.spreading_at(theta_k);
            }
        }
        if p == 0.0 {
            return 0.0;
        }
        p * group_velocity(k, self.depth_m) / k
    }

    /// Wavenumber of the spectral peak, rad/m.
    pub fn peak_wavenumber(&self) -> f64 {
        wavenumber(self.omega_p, self.depth_m)
    }

    /// Integral of P(k) over the annulus k_min <= |k| < k_max, m^2. D integrates to one over
    /// the circle, so this is the integral of S over [omega(k_min), omega(k_max)) (Gauss-Legendre
    /// on panels of 0.005 in ln omega: the JONSWAP peak is ~0.07 wide there).
    pub fn band_variance(&self, k_min: f64, k_max: f64) -> f64 {
        self.weighted_variance(k_min, k_max, |_| 1.0)
    }

    /// Integral of weight(|k|) P(k) over the annulus k_min <= |k| < k_max, m^2 (a layer's share
    /// under `OceanParams::partition`).
    pub fn weighted_variance(&self, k_min: f64, k_max: f64, weight: impl Fn(f64) -> f64) -> f64 {
        self.integrate(|w| self.s_omega(w), k_min, k_max, weight)
    }

    /// [`Spectrum::weighted_variance`] of one partition alone.
    pub fn part_variance(
        &self,
        part: Part,
        k_min: f64,
        k_max: f64,
        weight: impl Fn(f64) -> f64,
    ) -> f64 {
        self.integrate(|w| self.part_s_omega(part, w), k_min, k_max, weight)
    }

    fn integrate(
        &self,
        s: impl Fn(f64) -> f64,
        k_min: f64,
        k_max: f64,
        weight: impl Fn(f64) -> f64,
    ) -> f64 {
        // below 0.05 of a peak the spectrum holds nothing; above 1e4 peaks the omega^-5 tail
        // holds 1e-16 of the variance
        let (cut, peak) = self
            .swells
            .iter()
            .fold((self.omega_cut, self.omega_p), |(c, p), s| {
                (c.min(s.omega_p), p.max(s.omega_p))
            });
        let lo = self.omega(k_min).max(0.05 * cut);
        let hi = self.omega(k_max).min(1e4 * peak);
        if hi.is_nan() || lo.is_nan() || hi <= lo {
            return 0.0;
        }
        integrate_log(
            |w| s(w) * weight(wavenumber(w, self.depth_m)),
            lo,
            hi,
            0.005,
        )
    }

    /// Variance of the whole spectrum, m^2.
    pub fn total_variance(&self) -> f64 {
        self.band_variance(0.0, f64::INFINITY)
    }
}

/// Integral of f over [lo, hi] (lo > 0) by 5-point Gauss-Legendre on panels of width `du` in
/// u = ln x.
pub fn integrate_log(f: impl Fn(f64) -> f64, lo: f64, hi: f64, du: f64) -> f64 {
    const X: [f64; 5] = [
        0.0,
        -0.538_469_310_105_683_1,
        0.538_469_310_105_683_1,
        -0.906_179_845_938_664,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
        0.236_926_885_056_189_1,
    ];
    let (a, b) = (lo.ln(), hi.ln());
    let panels = ((b - a) / du).ceil().max(1.0) as usize;
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        for (x, w) in X.iter().zip(W) {
            let u = mid + 0.5 * h * x;
            let e = u.exp();
            sum += w * f(e) * e;
        }
    }
    sum * 0.5 * h
}

#[cfg(test)]
#[path = "spectrum_tests.rs"]
mod tests;
