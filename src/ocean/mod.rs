//! Ocean height-field model of paper section 2 (eqs. 1-7), built from the sea state in
//! [`crate::config::ocean`]. [`spectrum`] holds the oceanographic spectra (TMA, JONSWAP,
//! Pierson-Moskowitz, Phillips, directional spreading; Massel 1996, Horvath 2015) and their
//! conversion to the wavevector spectrum P(k) that seeds eq. 2; [`layer`] is one periodic FFT
//! realization (eqs. 1-3 plus exact spectral gradients); [`surface`] sums layers (eqs. 5-6)
//! and evaluates position (eq. 4), normal (eq. 7) and the Jacobian of the horizontal map;
//! [`preview`] draws it from above.

pub mod layer;
pub mod levels;
pub mod preview;
pub mod repeat;
pub mod slopes;
pub mod spectrum;
pub mod surface;

pub use crate::config::ocean::{
    Interp, LayerSpec, Layering, MAX_LAYERS, OceanParams, Partition, Preset, SpectrumKind,
    SpreadingKind, SwellParams, nyquist,
};
pub use layer::{FIELD_COUNT, Layer, Texel, field, jacobian};
pub use preview::write_preview_png;
pub use spectrum::{G, Spectrum};
pub use surface::{LayerSummary, OceanSummary, PartitionSummary, Sample, Sampler, Surface};

/// Errors of the ocean model. `Invalid` names the parameter as it appears in a config file.
#[derive(Debug, thiserror::Error)]
pub enum OceanError {
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    #[error("{field} must be {requirement} (got {got})")]
    Invalid {
        field: String,
        requirement: String,
        got: String,
    },
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
}

impl OceanError {
    pub(crate) fn invalid(
        field: impl Into<String>,
        requirement: impl Into<String>,
        got: impl std::fmt::Display,
    ) -> Self {
        OceanError::Invalid {
            field: field.into(),
            requirement: requirement.into(),
            got: crate::config::compact_number(got.to_string()),
        }
    }
}
