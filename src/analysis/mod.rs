//! The paper's statistics (section 5): per-pixel differences of relative luminance
//! ([`crate::color::luminance`]) of a scenario against the baseline, their azimuth-averaged
//! mean and standard deviation for every elevation row near the horizon (0 to -5 degrees by
//! default) and their band averages, corrected for Monte Carlo noise and given with confidence
//! intervals ([`error`]); [`plot`] draws them (the paper's Figure 5) and the renders side by
//! side (Figure 4). `crate::app::compare` runs the scenarios.

pub mod charts;
pub mod error;
pub mod plot;
