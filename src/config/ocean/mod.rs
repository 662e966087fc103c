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
    /// The paper's choice: 4 texels, error O(dx^2); its normals keep about 90 % of the
    /// spectrum's mean square slope.
    Bilinear,
    /// Catmull-Rom over 16 texels, error O(dx^3); about 3x the cost.
    Bicubic,
    /// Bilinear weights, each field's blend divided by its own standard deviation relative to
    /// a texel's, from the field's correlations between neighbouring texels (variance-preserving
    /// blending): every field keeps its grid variance at every point, so the slopes keep the
    /// spectrum's mean square where a bilinear blend of waves 2-5 texels long loses 10-25 % of it.
    VariancePreserving,
    /// Bilinear reads, of fields prefiltered for them: each wave's coefficient in the five
    /// derivative fields is divided by the square root of the power a bilinear read keeps of it
    /// on average over the positions between grid points, (2 + cos theta) / 3 per axis for a
    /// wave advancing theta radians a texel, and in h, Dx and Dz scaled so that the slope of
    /// their bilinear blend (the mesh's and the exact surface's) keeps the wave's slope power.
    /// The mapped normals and the surface keep the spectrum's mean square slope (where bilinear
    /// reads of waves 2-5 texels long lose 10-25 % of it), and both are closer to the direct
    /// Fourier sum point by point (docs/ocean.md, "Reading the layers"). The default.
    #[default]
    Prefiltered,
}

super::choice!(Interp { Bilinear => "bilinear", Bicubic => "bicubic", VariancePreserving => "variance-preserving", Prefiltered => "prefiltered" });

/// How the layers share the spectrum's wavenumbers (see [`OceanParams::partition`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Layering {
    /// Every wavenumber's energy is shared by all the layers that resolve it, with weights that
    /// sum to one (a smooth partition of unity in log |k|), so a wave band lives in several
    /// layers of unrelated periods and the sum does not repeat at any one of them.
    #[default]
    Overlap,
    /// Each layer holds its own band, which ends at half its Nyquist wavenumber where the next
    /// begins (the earlier scheme; every wave longer than the second layer's band
    /// repeats with the coarsest layer's period).
    Disjoint,
}

super::choice!(Layering { Overlap => "overlap", Disjoint => "disjoint" });

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
    /// Target RMS height of the wind sea, m: the realization (at `time_s`) is scaled to exactly
    /// this, or, with swells, to exactly the RMS of all partitions together,
    /// sqrt(rms^2 + sum of (Hs_swell / 4)^2), with the partitions in their asked proportions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_m: Option<f64>,
    /// Target significant wave height Hs of the wind sea, m, the other way to give the same
    /// target: Hs is the spectral Hm0 = 4 x RMS height, so it stands for an RMS of Hs / 4.
    /// At most one of `rms_m` and `hs_m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hs_m: Option<f64>,
    /// Peak period of the wind sea, s (TMA, JONSWAP): replaces the fetch law's peak, with a
    /// height target (`hs_m` or `rms_m`) for its level; the wind still sets the spreading.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tp_s: Option<f64>,
    /// A Beaufort force (1-12) that sets the wind, the fetch, the height and, for light winds,
    /// a background swell (see [`sea_state`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beaufort: Option<u8>,
    /// A Douglas sea state (1-9), as `beaufort` (see [`sea_state`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub douglas: Option<u8>,
    /// Swell partitions added to the wind sea.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub swell: Vec<SwellParams>,
    /// Direction the wind blows towards, degrees from +x towards +z.
    pub wind_dir_deg: f64,
    /// JONSWAP peak enhancement (TMA, JONSWAP).
    pub gamma: f64,
    /// Horizontal displacement scale f_d of eq. 3, with the sign that sharpens crests (see
    /// [`layer`]): 0 = pure height field.
    pub choppiness: f64,
    pub spectrum: SpectrumKind,
    pub spreading: SpreadingKind,
    /// Largest Mitsuyasu spreading exponent s (cos^2s); none = the formula as published. Goda's
    /// values: 10 for wind waves, 25 and 75 for short- and long-travelled swell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spreading_cap: Option<f64>,
    /// Coarsest first. In a file, `layers = "auto"` chooses them from the sea's peak
    /// ([`OceanParams::resolve_layers`]).
    #[serde(deserialize_with = "layers_or_auto")]
    pub layers: Vec<LayerSpec>,
    /// Whether `layers` was asked as "auto" (chosen again if the sea changes).
    #[serde(skip)]
    pub layers_auto: bool,
    /// How the layers share the wavenumbers.
    pub layering: Layering,
    /// Time t of eq. 2, s.
    pub time_s: f64,
    pub interp: Interp,
}

impl OceanParams {
    /// The wind sea's RMS height target: `rms_m`, or `hs_m` / 4; none without a target.
    pub fn wind_rms_target(&self) -> Option<f64> {
        self.rms_m.or(self.hs_m.map(|hs| hs / 4.0))
    }

    /// The RMS height the realization is scaled to: the wind sea's target and every swell's
    /// Hs / 4 summed in variance; none without a wind-sea target.
    pub fn rms_target(&self) -> Option<f64> {
        self.wind_rms_target().map(|w| {
            let swell: f64 = self.swell.iter().map(|s| (s.hs_m / 4.0).powi(2)).sum();
            (w * w + swell).sqrt()
        })
    }
}

impl Default for OceanParams {
    fn default() -> Self {
        OceanParams {
            wind_speed: 4.16,
            fetch_km: 204.5,
            depth_m: 997.9,
            rms_m: Some(0.225),
            hs_m: None,
            tp_s: None,
            beaufort: None,
            douglas: None,
            swell: Vec::new(),
            wind_dir_deg: 0.0,
            gamma: 3.3,
            choppiness: 1.0,
            spectrum: SpectrumKind::Tma,
            spreading: SpreadingKind::Mitsuyasu,
            spreading_cap: None,
            // Overlapping layers (see `partition`). The two 2048-texel layers of 12.7 and 10.3 km
            // (ratio 1.233) carry the spectral peak of case 22 (54 m) with 8-10 texels per
            // wavelength and periods beyond the 10 km the repeat metric looks at; 41.9 m takes
            // over from 21 m waves down (2 of its fundamentals); 5.83 m / 256 = 2.3 cm spacing
            // for 3 cm triangles near the camera.
            layers: vec![
                LayerSpec {
                    size_m: 12_700.0,
                    n: 2048,
                },
                LayerSpec {
                    size_m: 10_300.0,
                    n: 2048,
                },
                LayerSpec {
                    size_m: 41.9,
                    n: 512,
                },
                LayerSpec {
                    size_m: 5.83,
                    n: 256,
                },
            ],
            layers_auto: false,
            layering: Layering::Overlap,
            time_s: 0.0,
            interp: Interp::Prefiltered,
        }
    }
}

/// `layers` as a list of tables, or the text "auto" (read as no layers: the loaders choose them).
/// A visitor, not an untagged enum, so that a bad table's own error (an unknown key) comes
/// through.
fn layers_or_auto<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<LayerSpec>, D::Error> {
    struct V;
    impl<'de> serde::de::Visitor<'de> for V {
        type Value = Vec<LayerSpec>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("\"auto\" or an array of { size_m, n } tables")
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
            if v == "auto" {
                Ok(Vec::new())
            } else {
                Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
            }
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Deserialize::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(V)
}

fn positive(field: &str, v: f64) -> Result<(), ConfigError> {
    super::positive(&format!("ocean.{field}"), v)
}

/// Upper bounds of a sea state: past them the model describes no sea, and its arithmetic
/// overflows (an RMS height of 1e300 m) or its integrals never end (a wind of 1e308 m/s).
pub const WIND_MAX_M_S: f64 = 100.0;
pub const RMS_MAX_M: f64 = 25.0;
pub const FETCH_MAX_KM: f64 = 40_000.0;
pub const DEPTH_MAX_M: f64 = 11_000.0;

/// Finite, > 0 and at most `max` (`why` says what the bound is).
fn positive_at_most(field: &str, v: f64, max: f64, why: &str) -> Result<(), ConfigError> {
    positive(field, v)?;
    if v > max {
        let got = if v >= 1e6 {
            format!("{v:e}")
        } else {
            v.to_string()
        };
        return Err(invalid(
            &format!("ocean.{field}"),
            &format!("at most {max} ({why})"),
            got,
        ));
    }
    Ok(())
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
    /// The earlier default layers, kept for comparison: 400 / 47.3 / 5.83 m in disjoint bands
    /// (every wave longer than ~3 m lives in the 400 m layer, so the sea repeats every 400 m).
    pub fn tiling_layers() -> OceanParams {
        OceanParams {
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
            layering: Layering::Disjoint,
            ..OceanParams::default()
        }
    }

    /// Checks every field; the error names the first bad one, e.g.
    /// `ocean.wind_speed must be finite and > 0 (got -1)`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive_at_most(
            "wind_speed",
            self.wind_speed,
            WIND_MAX_M_S,
            "m/s at 10 m, about the strongest sustained wind measured in a tropical cyclone",
        )?;
        positive_at_most(
            "fetch_km",
            self.fetch_km,
            FETCH_MAX_KM,
            "km, the length of the equator",
        )?;
        positive_at_most(
            "depth_m",
            self.depth_m,
            DEPTH_MAX_M,
            "m; the deepest ocean is 10,935 m",
        )?;
        if let Some(rms) = self.rms_m {
            positive_at_most(
                "rms_m",
                rms,
                RMS_MAX_M,
                "m, a significant wave height of 100 m; the highest measured is about 19 m",
            )?;
        }
        if let Some(hs) = self.hs_m {
            positive_at_most(
                "hs_m",
                hs,
                4.0 * RMS_MAX_M,
                "m; the highest measured is about 19 m",
            )?;
            if self.rms_m.is_some() {
                return Err(invalid(
                    "ocean.hs_m",
                    "given without ocean.rms_m (both set the wave height: Hs = 4 x RMS; keep one)",
                    hs,
                ));
            }
        }
        if let Some(tp) = self.tp_s {
            if !(tp.is_finite() && tp > 0.5 && tp <= 30.0) {
                return Err(invalid("ocean.tp_s", "in (0.5, 30] s", tp));
            }
            if !matches!(self.spectrum, SpectrumKind::Tma | SpectrumKind::Jonswap) {
                return Err(invalid(
                    "ocean.tp_s",
                    "set only with spectrum = \"tma\" or \"jonswap\" (the others tie the peak to the wind)",
                    format!("{tp} with spectrum = \"{}\"", self.spectrum),
                ));
            }
            if self.rms_target().is_none() {
                return Err(invalid(
                    "ocean.tp_s",
                    "given with a height target, ocean.hs_m or ocean.rms_m (a peak period alone does not say how high the sea is)",
                    tp,
                ));
            }
        }
        if self.swell.len() > sea_state::MAX_SWELLS {
            return Err(invalid(
                "ocean.swell",
                &format!("at most {} partitions", sea_state::MAX_SWELLS),
                self.swell.len(),
            ));
        }
        for (i, s) in self.swell.iter().enumerate() {
            s.validate(i)?;
        }
        self.validate_preset()?;
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
        if let Some(cap) = self.spreading_cap {
            positive("spreading_cap", cap)?;
            if self.spreading != SpreadingKind::Mitsuyasu {
                return Err(invalid(
                    "ocean.spreading_cap",
                    "set only with spreading = \"mitsuyasu\" (it caps Mitsuyasu's exponent)",
                    format!("{cap} with spreading = \"{}\"", self.spreading),
                ));
            }
        }
        if self.layers.is_empty() || self.layers.len() > MAX_LAYERS {
            return Err(invalid(
                "ocean.layers",
                &format!(
                    "a list of 1 to {MAX_LAYERS} layers (\"auto\" is chosen by OceanParams::resolve_layers)"
                ),
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
            if i > 0 && l.size_m > self.layers[i - 1].size_m {
                return Err(invalid(
                    &format!("ocean.layers[{i}].size_m"),
                    &format!(
                        "at most the previous layer's {} m (layers go coarsest first)",
                        self.layers[i - 1].size_m
                    ),
                    l.size_m,
                ));
            }
            if i > 0 && self.layering == Layering::Overlap {
                let reach = (0..i)
                    .map(|j| overlap_bump(&self.layers, j).hi0)
                    .fold(0.0, f64::max);
                let start = overlap_bump(&self.layers, i).lo0;
                if start >= reach {
                    return Err(invalid(
                        &format!("ocean.layers[{i}].size_m"),
                        &format!(
                            "large enough that the layers leave no gap in |k|: its band starts at {start:.4} rad/m ({MIN_BAND_START_FUNDAMENTALS} fundamentals), the coarser layers' end at {reach:.4} rad/m"
                        ),
                        l.size_m,
                    ));
                }
            }
            if i > 0 && self.layering == Layering::Disjoint {
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

    /// How the layers share the spectrum: layer i's cell at wavevector k gets the fraction
    /// `partition().weight(i, |k|)` of P(k); the fractions sum to one over the layers at every
    /// |k| from half the coarsest layer's fundamental to the finest layer's Nyquist wavenumber.
    ///
    /// `Overlap`: layer i's raw share is a bump in ln |k| that is 1 from 4 of its fundamentals
    /// (2 pi / L) up to a quarter of its Nyquist wavenumber (8 texels per wavelength) and falls
    /// smoothly (smoothstep in ln |k|) to 0 at 2 fundamentals and at half Nyquist (4 texels per
    /// wavelength, the disjoint scheme's edge). The coarsest layer's bump starts at full height
    /// at half its fundamental and the finest one's runs at full height to its Nyquist. The
    /// weights are the bumps divided by their sum, so where k is resolved well by m layers each
    /// carries 1/m of it. Why: a wave band carried by one layer repeats with that layer's
    /// period, and the correlation of the summed height at a lag of one period is about the
    /// share of the variance that layer carries (see `crate::ocean::repeat`).
    ///
    /// `Disjoint`: the weights are 1 on [`OceanParams::bands`] and 0 elsewhere.
    pub fn partition(&self) -> Partition {
        let bumps = match self.layering {
            Layering::Overlap => (0..self.layers.len())
                .map(|i| overlap_bump(&self.layers, i))
                .collect(),
            Layering::Disjoint => self
                .bands()
                .into_iter()
                .map(|(lo, hi)| Bump {
                    lo0: lo,
                    lo1: lo,
                    hi1: hi,
                    hi0: hi,
                })
                .collect(),
        };
        Partition { bumps }
    }

    /// Wavenumber bands [k_min, k_max) of the disjoint scheme, rad/m. They tile one interval: layer 0
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

pub mod auto;
mod partition;
pub mod sea_state;
use partition::overlap_bump;
pub use partition::{Bump, Partition, band_edge, nyquist};
pub use sea_state::{Preset, SwellParams};

#[cfg(test)]
mod tests;
