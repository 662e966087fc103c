//! `layers = "auto"`: FFT layers chosen from the sea's shortest peak wavelength, so that the
//! summed surface repeats as little as periodic layers allow within the 10 km the repeat metric
//! looks at (`crate::ocean::repeat`; the figures are in docs/ocean.md).
//!
//! A peak carried by the two long layers (periods of 12.7 and 10.3 km, past the metric's window)
//! does not repeat; a peak carried by a layer of shorter period repeats with the share it holds.
//! Three tiers:
//! - peaks of [`LONG_PEAK_M`] and more: the default layers, whose 2048-texel long pair carries
//!   them (case 22's 54 m peak: 0.138);
//! - [`SHORT_PEAK_M`] to [`LONG_PEAK_M`]: the long pair at 4096 texels (2.5-3.1 m spacing), which
//!   carries waves down to about 17 m, and a 20.9 m layer below them (case 87's 24 m peak: 0.168;
//!   Beaufort 3's 17 m: 0.141), at 2.3 GB instead of 0.6 GB;
//! - [`MIN_MID_PEAK_M`] to [`SHORT_PEAK_M`]: no grid the memory allows gives a layer of period past
//!   10 km texels fine enough, so five mid-sized layers share the peak and their periods are
//!   chosen to coincide as little as possible (Beaufort 2's 5.3 m peak: 0.19-0.21 over seeds 1-3,
//!   against 0.45 on the default layers; a pure wind sea that short, with no swell to dilute it,
//!   still reads 0.36-0.55).
//!
//! Shorter peaks keep the default layers.

use super::{LayerSpec, OceanParams, SpectrumKind};

const G: f64 = 9.81;

/// Peak wavelength (m) from which the default layers carry the peak in their long pair.
pub const LONG_PEAK_M: f64 = 45.0;

/// The layers for peaks of [`LONG_PEAK_M`] and longer: the default list.
fn long_peak_layers() -> Vec<LayerSpec> {
    OceanParams::default().layers
}

/// The layers for shorter peaks: the long pair at 4096 texels and a 20.9 m layer that takes over
/// at 10 m waves (its band starts at 2 fundamentals, inside the 10.3 km layer's, which ends at
/// half Nyquist, 10.06 m).
fn short_peak_layers() -> Vec<LayerSpec> {
    [(12_700.0, 4096), (10_300.0, 4096), (20.9, 512), (5.83, 256)]
        .into_iter()
        .map(|(size_m, n)| LayerSpec { size_m, n })
        .collect()
}

/// Peak wavelength (m) under which the peak is shared by five mid-sized layers instead: between
/// the two seas measured on both (Douglas 2's 12.3 m peak: 0.36 on mid layers, 0.48 on the
/// 4096-texel pair; Beaufort 3's 17 m: 0.36 against 0.13).
pub const SHORT_PEAK_M: f64 = 14.0;

/// Shortest peak wavelength (m) given mid layers: below it the largest, 33.8 peaks, would start
/// its band (at 2 fundamentals) above where the long pair's ends (20.1 m waves).
pub const MIN_MID_PEAK_M: f64 = 1.2;

/// Mid-layer sizes in peak wavelengths: five periods whose multiples from 300 m to 10 km stay
/// at least 0.88 m apart at a 5.26 m peak (a random search over 24-34 peak wavelengths for the
/// largest smallest gap; nothing keeps them much further apart).
const MID_SIZES: [f64; 5] = [33.80, 32.72, 31.22, 24.94, 24.09];

/// The layers for peaks under [`SHORT_PEAK_M`] (down to [`MIN_MID_PEAK_M`]): the default long pair for swells,
/// five 1024-texel layers of 24-34 peak wavelengths sharing the peak (texels of 1/30 of it), and
/// the default finest layer: eight, the most a surface may have.
fn very_short_peak_layers(peak_m: f64) -> Vec<LayerSpec> {
    let mut l = OceanParams::default().layers;
    let finest = l.pop().expect("the default layers");
    l.truncate(2);
    l.extend(MID_SIZES.iter().map(|m| LayerSpec {
        size_m: m * peak_m,
        n: 1024,
    }));
    l.push(finest);
    l
}

/// Wavenumber of angular frequency `omega` on water `depth` deep (omega^2 = g k tanh(k h), by
/// fixed-point iteration from the deep-water value; it converges for every depth).
fn wavenumber(omega: f64, depth: f64) -> f64 {
    let mut k = omega * omega / G;
    for _ in 0..100 {
        k = 0.5 * (k + omega * omega / (G * (k * depth).tanh()));
    }
    k
}

impl OceanParams {
    /// The shortest peak wavelength of the sea's partitions, m: the wind sea's (from `tp_s`, or
    /// the spectrum's law for its peak) and each swell's.
    pub fn shortest_peak_wavelength(&self) -> f64 {
        let u = self.wind_speed;
        let omega_wind = match (self.tp_s, self.spectrum) {
            (Some(tp), _) => std::f64::consts::TAU / tp,
            (None, SpectrumKind::Tma | SpectrumKind::Jonswap) => {
                22.0 * (G * G / (u * self.fetch_km * 1000.0)).cbrt()
            }
            (None, SpectrumKind::PiersonMoskowitz) => 0.855 * G / u,
            (None, SpectrumKind::Phillips) => 0.8f64.powf(0.25) * G / u,
        };
        let omega = self
            .swell
            .iter()
            .map(|s| std::f64::consts::TAU / s.tp_s)
            .fold(omega_wind, f64::max);
        std::f64::consts::TAU / wavenumber(omega, self.depth_m)
    }

    /// Chooses the layers when they were asked as "auto" (or none are given): the default list
    /// for peaks of [`LONG_PEAK_M`] and more, the 4096-texel long pair otherwise (see the
    /// module doc). Explicit layers are kept.
    pub fn resolve_layers(&mut self) {
        if !(self.layers_auto || self.layers.is_empty()) {
            return;
        }
        self.layers_auto = true;
        let peak = self.shortest_peak_wavelength();
        self.layers = if peak >= LONG_PEAK_M {
            long_peak_layers()
        } else if peak >= SHORT_PEAK_M {
            short_peak_layers()
        } else if peak >= MIN_MID_PEAK_M {
            very_short_peak_layers(peak)
        } else {
            // ripples: mid layers this small would leave a gap under the long pair's band
            long_peak_layers()
        };
    }
}
