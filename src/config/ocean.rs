//! The sea state and the layers of its realization (paper section 2, Table 1): the spectrum
//! and spreading models by name, wind, fetch, depth, the target RMS height, the choppiness f_d
//! of eq. 3, and the FFT layers of eqs. 5-6 with the wavenumber band each one carries. Plain
//! data and its validation; `crate::ocean` builds the surface from it.

use serde::{Deserialize, Serialize};

use super::{ConfigError, invalid};

/// Most layers a surface may have; the ocean's `Sampler` keeps per-layer origins in a fixed array so it
/// stays `Copy`.
pub const MAX_LAYERS: usize = 8;

/// Frequency spectrum S(omega) of the sea state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SpectrumKind {
    /// JONSWAP times Kitaigorodskii's depth attenuation (Bouws et al. 1985), the paper's choice.
    #[default]
    Tma,
    /// Fetch-limited deep-water JONSWAP (Hasselmann et al. 1973).
    Jonswap,
    /// Fully developed sea (Pierson & Moskowitz 1964); fetch is ignored.
    PiersonMoskowitz,
    /// Tessendorf's Phillips spectrum written in frequency; fetch is ignored.
    Phillips,
}

super::choice!(SpectrumKind { Tma => "tma", Jonswap => "jonswap", PiersonMoskowitz => "pierson-moskowitz", Phillips => "phillips" });

/// Directional spreading D(theta; omega), normalised to 1 over the full circle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SpreadingKind {
    /// cos^2s(theta/2) with Mitsuyasu's frequency-dependent s (Mitsuyasu et al. 1975).
    #[default]
    Mitsuyasu,
    /// sech^2(beta theta) of Donelan, Hamilton & Hui (1985) with Banner's (1990) high-frequency beta.
    DonelanBanner,
    /// (2/pi) cos^2(theta) on the downwind half plane (the Phillips spectrum's classic factor).
    Cos2,
    /// No preferred direction.
    Uniform,
}

super::choice!(SpreadingKind { Mitsuyasu => "mitsuyasu", DonelanBanner => "donelan-banner", Cos2 => "cos2", Uniform => "uniform" });

/// How a layer's gridded fields are read between grid points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Interp {
    /// The paper's choice: 4 texels, error O(dx^2).
    #[default]
    Bilinear,
    /// Catmull-Rom over 16 texels, error O(dx^3); about 3x the cost.
    Bicubic,
}

super::choice!(Interp { Bilinear => "bilinear", Bicubic => "bicubic" });

/// One FFT realization: an `n` x `n` grid over a periodic `size_m` x `size_m` square.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    pub size_m: f64,
    pub n: usize,
}

/// Sea state and realization parameters. SI units except `fetch_km`. The default is close to
/// the paper's case 22 (Table 1) with three layers whose finest grid spacing is 2.3 cm.
///
/// In a configuration file every field may be omitted (it takes the default below), except that
/// an omitted `rms_m` means "no target" (TOML has no null to say so otherwise).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OceanParams {
    /// Wind speed at 10 m, m/s.
    pub wind_speed: f64,
    /// Fetch, km.
    pub fetch_km: f64,
    /// Water depth, m (finite-depth dispersion everywhere; TMA attenuation for `Tma`).
    pub depth_m: f64,
    /// Target RMS height, m: the realization (at `time_s`) is scaled to exactly this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_m: Option<f64>,
    /// Direction the wind blows towards, degrees from +x towards +z.
    pub wind_dir_deg: f64,
    /// JONSWAP peak enhancement (TMA, JONSWAP).
    pub gamma: f64,
    /// Horizontal displacement scale f_d of eq. 3, with the sign that sharpens crests (see
    /// [`layer`]): 0 = pure height field.
    pub choppiness: f64,
    pub spectrum: SpectrumKind,
    pub spreading: SpreadingKind,
    /// Coarsest first; each layer takes the wavenumber band above the previous one's.
    pub layers: Vec<LayerSpec>,
    /// Time t of eq. 2, s.
    pub time_s: f64,
    pub interp: Interp,
}

impl Default for OceanParams {
    fn default() -> Self {
        OceanParams {
            wind_speed: 4.16,
            fetch_km: 204.5,
            depth_m: 997.9,
            rms_m: Some(0.225),
            wind_dir_deg: 0.0,
            gamma: 3.3,
            choppiness: 1.0,
            spectrum: SpectrumKind::Tma,
            spreading: SpreadingKind::Mitsuyasu,
            // Extents in non-integer ratios (8.46, 8.11) so the sum does not repeat for
            // hundreds of km; 5.83 m / 256 = 2.3 cm spacing for 3 cm triangles near the camera.
            layers: vec![
                LayerSpec {
                    size_m: 400.0,
                    n: 512,
                },
                LayerSpec {
                    size_m: 47.3,
                    n: 512,
                },
                LayerSpec {
                    size_m: 5.83,
                    n: 256,
                },
            ],
            time_s: 0.0,
            interp: Interp::Bilinear,
        }
    }
}

fn positive(field: &str, v: f64) -> Result<(), ConfigError> {
    super::positive(&format!("ocean.{field}"), v)
}

fn finite(field: &str, v: f64) -> Result<(), ConfigError> {
    if !v.is_finite() {
        return Err(invalid(&format!("ocean.{field}"), "finite", v));
    }
    Ok(())
}

/// Smallest and largest grid a layer may have (power of two so the sampler wraps with a mask).
pub const MIN_N: usize = 16;
pub const MAX_N: usize = 4096;

/// Where a layer's band ends, as a fraction of its Nyquist wavenumber pi n / L. Half Nyquist
/// leaves at least four texels per wavelength, so bilinear reads keep >= 80 % of the amplitude
/// of the shortest wave; the finest layer alone runs to full Nyquist.
pub const BAND_SPLIT: f64 = 0.5;

/// Lowest wavenumber of a finer layer's band, in its own fundamentals 2 pi / L: below that a
/// layer has too few modes per ring to be isotropic.
pub const MIN_BAND_START_FUNDAMENTALS: f64 = 2.0;

impl OceanParams {
    /// Checks every field; the error names the first bad one, e.g.
    /// `ocean.wind_speed must be finite and > 0 (got -1)`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive("wind_speed", self.wind_speed)?;
        positive("fetch_km", self.fetch_km)?;
        positive("depth_m", self.depth_m)?;
        if let Some(rms) = self.rms_m {
            positive("rms_m", rms)?;
        }
        finite("wind_dir_deg", self.wind_dir_deg)?;
        if !self.gamma.is_finite() || self.gamma < 1.0 {
            return Err(invalid("ocean.gamma", "finite and >= 1", self.gamma));
        }
        if !self.choppiness.is_finite() || self.choppiness < 0.0 {
            return Err(invalid(
                "ocean.choppiness",
                "finite and >= 0",
                self.choppiness,
            ));
        }
        finite("time_s", self.time_s)?;
        if self.layers.is_empty() || self.layers.len() > MAX_LAYERS {
            return Err(invalid(
                "ocean.layers",
                &format!("a list of 1 to {MAX_LAYERS} layers"),
                format!("{} layers", self.layers.len()),
            ));
        }
        for (i, l) in self.layers.iter().enumerate() {
            positive(&format!("layers[{i}].size_m"), l.size_m)?;
            if !l.n.is_power_of_two() || l.n < MIN_N || l.n > MAX_N {
                return Err(invalid(
                    &format!("ocean.layers[{i}].n"),
                    &format!("a power of two in [{MIN_N}, {MAX_N}]"),
                    l.n,
                ));
            }
            if i > 0 {
                let kb = band_edge(&self.layers[i - 1]);
                let lo = MIN_BAND_START_FUNDAMENTALS * std::f64::consts::TAU / kb;
                // The band [kb, kmax) must span at least a factor 2 in wavenumber; kmax is the
                // layer's Nyquist wavenumber for the last layer, BAND_SPLIT of it otherwise.
                let split = if i + 1 == self.layers.len() {
                    1.0
                } else {
                    BAND_SPLIT
                };
                let hi = split * std::f64::consts::PI * l.n as f64 / (2.0 * kb);
                if l.size_m < lo || l.size_m > hi {
                    return Err(invalid(
                        &format!("ocean.layers[{i}].size_m"),
                        &format!(
                            "in [{lo:.4}, {hi:.4}] so its band starts at the previous layer's band edge ({kb:.4} rad/m)"
                        ),
                        l.size_m,
                    ));
                }
            }
        }
        Ok(())
    }

    /// Wavenumber bands [k_min, k_max) of the layers, rad/m. They tile one interval: layer 0
    /// starts at half its fundamental (the DC cell's edge), each later one where the previous
    /// ends, and the last runs to its Nyquist wavenumber.
    pub fn bands(&self) -> Vec<(f64, f64)> {
        let m = self.layers.len();
        (0..m)
            .map(|i| {
                let lo = if i == 0 {
                    std::f64::consts::PI / self.layers[0].size_m
                } else {
                    band_edge(&self.layers[i - 1])
                };
                let hi = if i + 1 == m {
                    nyquist(&self.layers[i])
                } else {
                    band_edge(&self.layers[i])
                };
                (lo, hi)
            })
            .collect()
    }
}

pub fn nyquist(l: &LayerSpec) -> f64 {
    std::f64::consts::PI * l.n as f64 / l.size_m
}

pub fn band_edge(l: &LayerSpec) -> f64 {
    BAND_SPLIT * nyquist(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err_of(f: impl FnOnce(&mut OceanParams)) -> String {
        let mut p = OceanParams::default();
        f(&mut p);
        p.validate().expect_err("must be rejected").to_string()
    }

    #[test]
    fn default_is_valid_and_bands_tile() {
        let p = OceanParams::default();
        p.validate().unwrap();
        let b = p.bands();
        assert_eq!(b.len(), 3);
        for i in 1..b.len() {
            assert_eq!(b[i - 1].1, b[i].0);
        }
        assert!(b.iter().all(|(lo, hi)| lo < hi));
        // finest spacing 2-3 cm, as the paper suggests for 3 cm triangles
        let l = p.layers.last().unwrap();
        let dx = l.size_m / l.n as f64;
        assert!((0.02..=0.03).contains(&dx), "{dx}");
    }

    #[test]
    fn bad_input_names_the_parameter() {
        assert_eq!(
            err_of(|p| p.wind_speed = -1.0),
            "ocean.wind_speed must be finite and > 0 (got -1)"
        );
        assert!(err_of(|p| p.wind_speed = 0.0).starts_with("ocean.wind_speed"));
        assert!(
            err_of(|p| p.wind_speed = f64::NAN)
                .contains("ocean.wind_speed must be finite and > 0 (got NaN)")
        );
        assert!(err_of(|p| p.fetch_km = 0.0).starts_with("ocean.fetch_km"));
        assert!(err_of(|p| p.fetch_km = f64::INFINITY).starts_with("ocean.fetch_km"));
        assert!(err_of(|p| p.depth_m = -3.0).starts_with("ocean.depth_m"));
        assert!(err_of(|p| p.depth_m = f64::NAN).starts_with("ocean.depth_m"));
        assert!(err_of(|p| p.rms_m = Some(0.0)).starts_with("ocean.rms_m"));
        assert!(err_of(|p| p.gamma = 0.5).starts_with("ocean.gamma"));
        assert!(err_of(|p| p.choppiness = f64::NAN).starts_with("ocean.choppiness"));
        assert!(err_of(|p| p.wind_dir_deg = f64::NAN).starts_with("ocean.wind_dir_deg"));
        assert!(err_of(|p| p.time_s = f64::INFINITY).starts_with("ocean.time_s"));
        assert!(err_of(|p| p.layers.clear()).starts_with("ocean.layers must be"));
        assert!(
            err_of(|p| p.layers[1].n = 500).starts_with("ocean.layers[1].n must be a power of two")
        );
        assert!(err_of(|p| p.layers[0].n = 8).starts_with("ocean.layers[0].n"));
        assert!(
            err_of(|p| p.layers[2].size_m = -5.83)
                .starts_with("ocean.layers[2].size_m must be finite")
        );
        // a finer layer too small to start its band at the coarser layer's edge
        assert!(
            err_of(|p| p.layers[1].size_m = 3.0).starts_with("ocean.layers[1].size_m must be in [")
        );
        // or so large that its band would be nearly empty
        assert!(
            err_of(|p| p.layers[2].size_m = 40.0)
                .starts_with("ocean.layers[2].size_m must be in [")
        );
    }

    #[test]
    fn serde_round_trip_and_unknown_keys() {
        let p = OceanParams::default();
        let json = serde_json::to_string(&p).unwrap();
        let q: OceanParams = serde_json::from_str(&json).unwrap();
        assert_eq!(p, q);
        let partial: OceanParams =
            toml::from_str("wind_speed = 2.38\nspectrum = \"pierson-moskowitz\"\n").unwrap();
        assert_eq!(partial.wind_speed, 2.38);
        assert_eq!(partial.spectrum, SpectrumKind::PiersonMoskowitz);
        assert_eq!(partial.rms_m, None);
        assert_eq!(partial.layers, p.layers);
        let bad = toml::from_str::<OceanParams>("wind_sped = 3.0\n")
            .unwrap_err()
            .to_string();
        assert!(bad.contains("wind_sped"), "{bad}");
        let bad = toml::from_str::<OceanParams>("[[layers]]\nsize_m = 10.0\nn = 64\nextra = 1\n")
            .unwrap_err()
            .to_string();
        assert!(bad.contains("extra"), "{bad}");
    }
}
