//! The sea state in a mariner's terms: swell partitions beside the wind sea, and the Beaufort
//! and Douglas presets, which resolve into the explicit keys (wind, fetch, the wind sea's
//! significant wave height and, for light winds, a background swell) before anything is built.
//!
//! The presets' sources: the Beaufort wind ranges and "probable" wave heights of WMO's Manual on
//! Marine Meteorological Services (WMO-No. 558, Annex I), read as significant wave heights; the
//! Douglas sea-state code (WMO code table 3700) and its height ranges. The wind sea's fetch comes
//! from JONSWAP's growth law Hs = 1.6e-3 sqrt(g F / U^2) U^2 / g (Hasselmann et al. 1973), which
//! meets the fully developed Pierson-Moskowitz Hs = 0.21 U^2 / g at g F / U^2 = 17 035, the
//! project's full-development fetch.

use serde::{Deserialize, Serialize};

use super::super::{ConfigError, invalid};
use super::OceanParams;

/// Standard gravity, m/s^2 (the spectrum's value).
const G: f64 = 9.81;

/// g F / U^2 of a fully developed sea (the spectrum's `FULLY_DEVELOPED_FETCH`).
pub const FULLY_DEVELOPED_FETCH: f64 = 17_035.0;

/// JONSWAP's fetch law: Hs g / U^2 = HS_GROWTH sqrt(g F / U^2).
const HS_GROWTH: f64 = 1.6e-3;

/// Most swell partitions a sea may have.
pub const MAX_SWELLS: usize = 4;

/// One swell partition: a JONSWAP-shaped frequency spectrum with its own peak, height, direction
/// and a cos-2s spreading of fixed exponent, added to the wind sea in the same layers (linear
/// waves superpose).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SwellParams {
    /// Significant wave height of this partition alone, m.
    pub hs_m: f64,
    /// Peak period, s.
    pub tp_s: f64,
    /// Direction the swell travels towards, degrees from +x towards +z (as `wind_dir_deg`).
    #[serde(default)]
    pub dir_deg: f64,
    /// cos-2s spreading exponent s (Goda 1985: 25 for swell with a short decay distance, 75 for
    /// long-travelled swell).
    #[serde(default = "SwellParams::default_spreading")]
    pub spreading_s: f64,
    /// JONSWAP peak enhancement of its spectrum.
    #[serde(default = "SwellParams::default_gamma")]
    pub gamma: f64,
}

impl SwellParams {
    fn default_spreading() -> f64 {
        25.0
    }
    fn default_gamma() -> f64 {
        3.3
    }

    /// A swell of height `hs_m` and period `tp_s` travelling towards `dir_deg`, with the default
    /// spreading and peak enhancement.
    pub fn new(hs_m: f64, tp_s: f64, dir_deg: f64) -> SwellParams {
        SwellParams {
            hs_m,
            tp_s,
            dir_deg,
            spreading_s: Self::default_spreading(),
            gamma: Self::default_gamma(),
        }
    }

    pub(super) fn validate(&self, i: usize) -> Result<(), ConfigError> {
        let field = |name: &str| format!("ocean.swell[{i}].{name}");
        let check = |name: &str, v: f64, lo: f64, hi: f64, what: &str| {
            if !(v.is_finite() && v > lo && v <= hi) {
                return Err(invalid(&field(name), what, v));
            }
            Ok(())
        };
        check(
            "hs_m",
            self.hs_m,
            0.0,
            25.0,
            "in (0, 25] m (the highest swells measured are about 20 m)",
        )?;
        check(
            "tp_s",
            self.tp_s,
            1.0,
            30.0,
            "in (1, 30] s (the longest ocean swells have periods near 25 s)",
        )?;
        check("spreading_s", self.spreading_s, 0.0, 1000.0, "in (0, 1000]")?;
        if !self.dir_deg.is_finite() {
            return Err(invalid(&field("dir_deg"), "finite", self.dir_deg));
        }
        if !(self.gamma.is_finite() && (1.0..=20.0).contains(&self.gamma)) {
            return Err(invalid(&field("gamma"), "in [1, 20]", self.gamma));
        }
        Ok(())
    }
}

/// One row of a preset table: the wind speed at 10 m it stands for and the significant wave
/// height of the open sea.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresetRow {
    pub number: u8,
    pub name: &'static str,
    /// The published wind range, m/s (Beaufort), or none (Douglas).
    pub wind_range_m_s: Option<(f64, f64)>,
    /// The published wave-height range, m: Beaufort's probable and maximum heights, Douglas'
    /// bounds (the last one open: its upper bound is the lower one).
    pub height_range_m: (f64, f64),
    /// Wind speed the preset uses, m/s.
    pub wind_m_s: f64,
    /// Significant wave height the preset asks for, m.
    pub hs_m: f64,
}

/// Beaufort forces 1-12: WMO-No. 558 wind ranges (m/s at 10 m) and probable / maximum wave
/// heights (m). The preset blows the range's middle (force 12, open above, its lower bound) and
/// asks for the probable height.
pub const BEAUFORT: [(u8, &str, f64, f64, f64, f64); 12] = [
    (1, "light air", 0.3, 1.5, 0.1, 0.1),
    (2, "light breeze", 1.6, 3.3, 0.2, 0.3),
    (3, "gentle breeze", 3.4, 5.4, 0.6, 1.0),
    (4, "moderate breeze", 5.5, 7.9, 1.0, 1.5),
    (5, "fresh breeze", 8.0, 10.7, 2.0, 2.5),
    (6, "strong breeze", 10.8, 13.8, 3.0, 4.0),
    (7, "near gale", 13.9, 17.1, 4.0, 5.5),
    (8, "gale", 17.2, 20.7, 5.5, 7.5),
    (9, "strong gale", 20.8, 24.4, 7.0, 10.0),
    (10, "storm", 24.5, 28.4, 9.0, 12.5),
    (11, "violent storm", 28.5, 32.6, 11.5, 16.0),
    (12, "hurricane", 32.7, 32.7, 14.0, 14.0),
];

/// Douglas sea states 1-9 (WMO code table 3700): name and wave-height range, m. The preset asks
/// for the range's middle (state 9, open above, its lower bound).
pub const DOUGLAS: [(u8, &str, f64, f64); 9] = [
    (1, "calm (rippled)", 0.0, 0.1),
    (2, "smooth (wavelets)", 0.1, 0.5),
    (3, "slight", 0.5, 1.25),
    (4, "moderate", 1.25, 2.5),
    (5, "rough", 2.5, 4.0),
    (6, "very rough", 4.0, 6.0),
    (7, "high", 6.0, 9.0),
    (8, "very high", 9.0, 14.0),
    (9, "phenomenal", 14.0, 14.0),
];

/// Peak period of the background swell a light-wind preset adds, s: the global mean swell
/// period is 10-12 s (Semedo et al. 2011, "A global view on the wind sea and swell climate").
pub const BACKGROUND_SWELL_TP_S: f64 = 10.0;

/// Significant wave height of a fully developed wind sea, m: 0.21 U^2 / g as JONSWAP's growth
/// law reaches it (Pierson-Moskowitz).
pub fn fully_developed_hs(u: f64) -> f64 {
    HS_GROWTH * FULLY_DEVELOPED_FETCH.sqrt() * u * u / G
}

/// Wind speed whose fully developed sea has significant height `hs`, m/s.
pub fn fully_developed_wind(hs: f64) -> f64 {
    (hs * G / (HS_GROWTH * FULLY_DEVELOPED_FETCH.sqrt())).sqrt()
}

/// Fetch (km) at which JONSWAP's growth law gives a wind sea of height `hs` under wind `u`,
/// at most the full-development fetch.
pub fn fetch_for(hs: f64, u: f64) -> f64 {
    let x = (hs * G / (HS_GROWTH * u * u))
        .powi(2)
        .min(FULLY_DEVELOPED_FETCH);
    x * u * u / G / 1000.0
}

/// A mariner's name for a sea state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    Beaufort(u8),
    Douglas(u8),
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Preset::Beaufort(n) => write!(f, "ocean.beaufort = {n}"),
            Preset::Douglas(n) => write!(f, "ocean.douglas = {n}"),
        }
    }
}

impl Preset {
    /// The preset's table row, or `None` when the number is outside the table.
    pub fn row(self) -> Option<PresetRow> {
        match self {
            Preset::Beaufort(n) => {
                BEAUFORT
                    .iter()
                    .find(|r| r.0 == n)
                    .map(|&(number, name, lo, hi, probable, max)| PresetRow {
                        number,
                        name,
                        wind_range_m_s: Some((lo, hi)),
                        height_range_m: (probable, max),
                        wind_m_s: 0.5 * (lo + hi),
                        hs_m: probable,
                    })
            }
            Preset::Douglas(n) => {
                DOUGLAS
                    .iter()
                    .find(|r| r.0 == n)
                    .map(|&(number, name, lo, hi)| {
                        let hs = 0.5 * (lo + hi);
                        PresetRow {
                            number,
                            name,
                            wind_range_m_s: None,
                            height_range_m: (lo, hi),
                            wind_m_s: fully_developed_wind(hs),
                            hs_m: hs,
                        }
                    })
            }
        }
    }

    /// The explicit sea the preset stands for: wind speed, fetch (km), the wind sea's target
    /// Hs, and a background swell when the wind alone cannot hold the preset's height.
    ///
    /// The policy: the wind sea is fetch-limited at the fetch where JONSWAP's growth law gives the
    /// preset's height, and fully developed if even full development holds less. Beaufort 1-5
    /// are that case: WMO's probable heights of 0.1, 0.2, 0.6, 1 and 2 m are 5.8, 1.57, 1.46,
    /// 1.05 and 1.07 times what a fully developed sea under the range's middle wind holds
    /// (0.21 U^2 / g), because the open sea's light-wind waves are partly swell. The rest of the variance,
    /// Hs_swell^2 = Hs^2 - Hs_wind^2, goes into a swell of [`BACKGROUND_SWELL_TP_S`] travelling
    /// with the wind, so the total is the preset's height and no wind sea is steeper than
    /// nature's.
    pub fn sea(self) -> Option<(f64, f64, f64, Option<SwellParams>)> {
        let row = self.row()?;
        let u = row.wind_m_s;
        let wind_hs = row.hs_m.min(fully_developed_hs(u));
        let swell2 = row.hs_m * row.hs_m - wind_hs * wind_hs;
        // a remainder under 1 % of the variance is rounding, not a swell
        let swell = (swell2 > 1e-2 * row.hs_m * row.hs_m)
            .then(|| SwellParams::new(swell2.sqrt(), BACKGROUND_SWELL_TP_S, 0.0));
        Some((u, fetch_for(wind_hs, u), wind_hs, swell))
    }
}

impl OceanParams {
    /// The preset this sea state names, if any (validation refuses two).
    pub fn preset(&self) -> Option<Preset> {
        self.beaufort
            .map(Preset::Beaufort)
            .or(self.douglas.map(Preset::Douglas))
    }

    /// Writes the preset's sea into the explicit keys: wind speed, fetch, the wind sea's Hs
    /// target (no RMS target, no peak period) and, for light winds, the background swell as the
    /// first swell (travelling with the wind), before any swells of the scene's own. (The loaders make
    /// a preset's layers "auto" when the scene names none.) Idempotent;
    /// nothing happens without a preset or with an unknown one (validation names it).
    pub fn apply_preset(&mut self) {
        let Some((u, fetch_km, hs, swell)) = self.preset().and_then(Preset::sea) else {
            return;
        };
        self.wind_speed = u;
        self.fetch_km = fetch_km;
        self.hs_m = Some(hs);
        self.rms_m = None;
        self.tp_s = None;
        if let Some(mut s) = swell {
            s.dir_deg = self.wind_dir_deg;
            if self.swell.first() != Some(&s) {
                self.swell.insert(0, s);
            }
        }
    }

    /// Drops the preset and the background swell it added, keeping the explicit keys it set.
    pub fn clear_preset(&mut self) {
        if let Some((.., Some(mut s))) = self.preset().and_then(Preset::sea) {
            s.dir_deg = self.wind_dir_deg;
            if self.swell.first() == Some(&s) {
                self.swell.remove(0);
            }
        }
        (self.beaufort, self.douglas) = (None, None);
    }

    /// A preset's number is in its table, only one preset is named, and the keys it sets hold
    /// its values (a key changed after the preset was applied is named with the preset).
    pub(super) fn validate_preset(&self) -> Result<(), ConfigError> {
        if let (Some(b), Some(d)) = (self.beaufort, self.douglas) {
            return Err(invalid(
                "ocean.douglas",
                "given without ocean.beaufort (both name the sea state; keep one)",
                format!("{d} with ocean.beaufort = {b}"),
            ));
        }
        let Some(preset) = self.preset() else {
            return Ok(());
        };
        let (field, range) = match preset {
            Preset::Beaufort(_) => ("ocean.beaufort", "a Beaufort force in 1..=12"),
            Preset::Douglas(_) => ("ocean.douglas", "a Douglas sea state in 1..=9"),
        };
        let Some((u, fetch_km, hs, swell)) = preset.sea() else {
            let n = self.beaufort.or(self.douglas).unwrap_or_default();
            return Err(invalid(field, range, n));
        };
        let clash = |key: &str, got: String| {
            invalid(
                key,
                &format!("left to {preset}, which sets it (give the preset or the key, not both)"),
                got,
            )
        };
        if self.wind_speed != u {
            return Err(clash("ocean.wind_speed", self.wind_speed.to_string()));
        }
        if self.fetch_km != fetch_km {
            return Err(clash("ocean.fetch_km", self.fetch_km.to_string()));
        }
        if let Some(rms) = self.rms_m {
            return Err(clash("ocean.rms_m", rms.to_string()));
        }
        if self.hs_m != Some(hs) {
            return Err(clash("ocean.hs_m", format!("{:?}", self.hs_m)));
        }
        if let Some(tp) = self.tp_s {
            return Err(clash("ocean.tp_s", tp.to_string()));
        }
        if let Some(mut s) = swell {
            s.dir_deg = self.wind_dir_deg;
            if self.swell.first() != Some(&s) {
                return Err(clash(
                    "ocean.swell[0]",
                    format!(
                        "{:?} (the preset's background swell goes first)",
                        self.swell.first()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The keys a preset sets: a scene file that names a preset must leave them out.
pub const PRESET_KEYS: [&str; 5] = ["wind_speed", "fetch_km", "rms_m", "hs_m", "tp_s"];
