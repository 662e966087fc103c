//! One periodic FFT realization of the ocean (paper eqs. 1-3): random amplitudes h0(k) drawn
//! from P(k) of [`super::spectrum`], evolved in time by eq. 2 with finite-depth dispersion, and
//! transformed with rustfft into eight real fields on an n x n grid over an L x L square: h,
//! D = (Dx, Dz) and the exact spectral derivatives dh/dx, dh/dz, dDx/dx, dDz/dz, dDx/dz
//! (= dDz/dx) that eq. 7 needs. Reads between grid points are bilinear with periodic wrap (the
//! paper's choice) or Catmull-Rom bicubic; [`Layer::eval_direct`] sums the Fourier series
//! directly and is the oracle for both.
//!
//! Conventions that differ from a literal reading of the paper, and why:
//! - Eq. 2 multiplies h0(k) by exp(+i omega t), so h0(k) carries the wave that travels towards
//!   -k. h0(k) is therefore drawn from P(-k), which makes the energy of P(k) travel along k:
//!   waves run downwind.
//! - With D = f_d sum(-i k/k) h~ (eq. 3) a wave h = cos(k x) gets Dx = f_d sin(k x): positive
//!   f_d stretches crests and folds troughs. The layer uses D = lambda sum(+i k/k) h~ with
//!   lambda = `choppiness` >= 0 (eq. 3 with f_d = -lambda), the Gerstner sense, where crests
//!   sharpen.
//!
//! Two real fields share one complex FFT (the transform of A + iB is a + ib when A and B are
//! Hermitian), so the eight fields take four 2-D transforms. Texels store the fields
//! interleaved, `[f32; 8]` = 32 bytes, so a bilinear read touches four contiguous records.
//!
//! Interpolation error against the direct sum (RMS error over RMS value). One 47.3 m / 128
//! layer of case 22 whose band spans 4 fundamentals to half Nyquist, like the default middle
//! layer (test `interpolation_error_against_direct_sum`): h bilinear 2.8e-2, bicubic 6.1e-3;
//! dh/dx bilinear 6.9e-2, bicubic 1.7e-2. A three-layer surface, whose finest layer runs to full
//! Nyquist (test `sampler_matches_direct_sum_of_layers` in [`super::surface`]): h 1.8e-2 vs
//! 3.4e-3, gradients 0.14-0.19 vs 0.07-0.11, dominated by the finest layer's top octave (2-4
//! texels per wavelength).

use std::f64::consts::TAU;
use std::sync::Arc;

use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use super::OceanError;
use super::spectrum::Spectrum;
use crate::config::ocean::{MAX_N, MIN_N};
use crate::rng::splitmix64;

mod amplitudes;
mod fields;
mod level;
mod read;

pub use fields::FieldPlanes;
pub(crate) use fields::h_tilde_of;

#[cfg(test)]
use read::{LANE_RANGE, catmull_rom, split, split_lanes};
pub(crate) use read::{LagCorrelations, add_texel};
pub use read::{read_cross_transfer, read_power_transfer};

/// Number of fields per texel.
pub const FIELD_COUNT: usize = 8;

/// Indices into a texel.
pub mod field {
    pub const H: usize = 0;
    pub const DX: usize = 1;
    pub const DZ: usize = 2;
    pub const DH_DX: usize = 3;
    pub const DH_DZ: usize = 4;
    pub const DDX_DX: usize = 5;
    pub const DDZ_DZ: usize = 6;
    /// dDx/dz, which equals dDz/dx.
    pub const DDX_DZ: usize = 7;
}

/// The eight fields at one grid point, in [`field`] order.
pub type Texel = [f32; FIELD_COUNT];

/// The derivative fields, [`field::DH_DX`] to [`field::DDX_DZ`] (the last five of a texel):
/// all that a normal needs.
pub const SLOPES: std::ops::Range<usize> = field::DH_DX..FIELD_COUNT;
/// The five derivative fields at one point, in [`field`] order from [`field::DH_DX`].
pub type Slopes = [f32; FIELD_COUNT - field::DH_DX];

/// The derivative fields of a texel (or of summed fields).
#[inline]
pub fn slopes(t: &Texel) -> Slopes {
    std::array::from_fn(|i| t[SLOPES.start + i])
}

type C32 = Complex<f32>;

/// What [`Layer::compute_fields`] measures of the grid points as it writes them: the sums
/// while it runs, the means once it is done.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridStats {
    /// Mean of h^2 (the layer's variance over its period), m^2; with prefiltered fields, by
    /// Parseval from the coefficients before the prefilter (the texels hold more).
    pub variance: f64,
    /// Mean of |grad h|^2 (the exact spectral gradients) of the sea: with prefiltered slope
    /// fields, by Parseval from the coefficients before the prefilter (the texels hold more).
    pub mss: f64,
    /// The largest |dDx/dx|, |dDz/dz| and |dDx/dz|: a bound on what any bilinear read returns.
    pub max_strain: [f32; 3],
}

impl GridStats {
    #[inline]
    fn add(&mut self, t: &Texel) {
        self.variance += (t[field::H] as f64).powi(2);
        self.mss += (t[field::DH_DX] as f64).powi(2) + (t[field::DH_DZ] as f64).powi(2);
        for (m, f) in self
            .max_strain
            .iter_mut()
            .zip([field::DDX_DX, field::DDZ_DZ, field::DDX_DZ])
        {
            *m = m.max(t[f].abs());
        }
    }

    fn merge(&self, o: &GridStats) -> GridStats {
        GridStats {
            variance: self.variance + o.variance,
            mss: self.mss + o.mss,
            max_strain: std::array::from_fn(|i| self.max_strain[i].max(o.max_strain[i])),
        }
    }
}

/// One periodic realization: amplitudes, dispersion and the gridded fields at one time.
pub struct Layer {
    size_m: f64,
    n: usize,
    k_min: f64,
    k_max: f64,
    choppiness: f64,
    time_s: f64,
    /// h0(k) of the cells the band can reach, kx-major in `cells`' layout, zero outside the
    /// band.
    h0: Vec<C32>,
    cells: amplitudes::BandCells,
    /// Water depth for the dispersion relation: omega(|k|) is computed where h0 is non-zero
    /// rather than stored (64 MB for a 2048-texel layer).
    depth_m: f64,
    expected_variance: f64,
    /// Texels, z-major (index iz * n + ix); texel (ix, iz) is at (ix L/n, iz L/n).
    fields: Vec<Texel>,
    /// The fields' grid statistics, measured as they were written.
    grid: GridStats,
    /// Each field's correlations between neighbouring texels, for variance-preserving reads:
    /// computed on first use, forgotten when the fields change.
    lag_correlations: std::sync::OnceLock<LagCorrelations>,
    /// Whether the fields are prefiltered for bilinear reads ([`Layer::set_prefilter`]).
    prefilter: bool,
    fft: Arc<dyn Fft<f32>>,
    inv_dx: f64,
}

#[inline]
pub(crate) fn signed_index(i: usize, n: usize) -> f64 {
    if i < n / 2 {
        i as f64
    } else {
        i as f64 - n as f64
    }
}

impl Layer {
    /// A realization of `spectrum` on an `n` x `n` grid over `size_m`, keeping wavevectors with
    /// `band.0 <= |k| < band.1` (clipped to the Nyquist disk), with fields at `time_s`.
    /// `seed` fully determines the amplitudes, whatever the thread count.
    pub fn new(
        spectrum: &Spectrum,
        size_m: f64,
        n: usize,
        band: (f64, f64),
        choppiness: f64,
        seed: u64,
        time_s: f64,
    ) -> Result<Layer, OceanError> {
        Layer::with_weight(
            spectrum,
            size_m,
            n,
            band,
            &|_| 1.0,
            choppiness,
            seed,
            time_s,
        )
    }

    /// Like [`Layer::new`], carrying the fraction
    /// `weight(|k|)` of P(k), which must be 0 outside `band.0 <= |k| < band.1` (the band is
    /// clipped to the Nyquist disk), with fields at `time_s`. `seed` fully determines the
    /// amplitudes, whatever the thread count.
    #[allow(clippy::too_many_arguments)]
    pub fn with_weight(
        spectrum: &Spectrum,
        size_m: f64,
        n: usize,
        band: (f64, f64),
        weight: &(dyn Fn(f64) -> f64 + Sync),
        choppiness: f64,
        seed: u64,
        time_s: f64,
    ) -> Result<Layer, OceanError> {
        let mut layer = Layer::drawn(spectrum, size_m, n, band, weight, choppiness, seed, time_s)?;
        layer.compute_fields(time_s);
        Ok(layer)
    }

    /// The layer of [`Layer::with_weight`] with its amplitudes drawn and its fields not yet
    /// computed: [`Layer::compute_fields`] (or `_in`) must run before anything reads it.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn drawn(
        spectrum: &Spectrum,
        size_m: f64,
        n: usize,
        band: (f64, f64),
        weight: &(dyn Fn(f64) -> f64 + Sync),
        choppiness: f64,
        seed: u64,
        time_s: f64,
    ) -> Result<Layer, OceanError> {
        if !size_m.is_finite() || size_m <= 0.0 {
            return Err(OceanError::invalid(
                "layer size_m",
                "finite and > 0",
                size_m,
            ));
        }
        if !n.is_power_of_two() || !(MIN_N..=MAX_N).contains(&n) {
            return Err(OceanError::invalid(
                "layer n",
                format!("a power of two in [{MIN_N}, {MAX_N}]"),
                n,
            ));
        }
        if band.0.is_nan() || band.1.is_nan() || band.0 < 0.0 || band.1 <= band.0 {
            return Err(OceanError::invalid(
                "layer band",
                "0 <= k_min < k_max",
                format!("{band:?}"),
            ));
        }
        let dk = TAU / size_m;
        let k_nyquist = 0.5 * n as f64 * dk;
        let band = (band.0, band.1.min(k_nyquist));
        // a cell's sub-grid reaches dk / sqrt(2) past its centre; the table's nodes depend on
        // the grid, not on the band, so a cell's amplitude does not either
        let point = amplitudes::PointSpectrum::new(spectrum, weight, k_nyquist + dk);
        Ok(Layer::build(
            &point,
            spectrum.depth_m,
            size_m,
            n,
            band,
            choppiness,
            seed,
            time_s,
        ))
    }

    /// The layer of [`Layer::with_weight`] once its arguments are checked and its band clipped,
    /// drawing from `point` (the radial table or, in tests, the exact spectrum).
    #[allow(clippy::too_many_arguments)]
    fn build(
        point: &amplitudes::PointSpectrum,
        depth_m: f64,
        size_m: f64,
        n: usize,
        band: (f64, f64),
        choppiness: f64,
        seed: u64,
        time_s: f64,
    ) -> Layer {
        let dk = TAU / size_m;
        let cells = amplitudes::BandCells::new(n, dk, band.1);
        let (h0, expected_variance) = amplitudes::draw(point, &cells, dk, band, splitmix64(seed));
        let fft = FftPlanner::<f32>::new().plan_fft_inverse(n);
        Layer {
            size_m,
            n,
            k_min: band.0,
            k_max: band.1,
            choppiness,
            time_s,
            h0,
            cells,
            depth_m,
            expected_variance,
            fields: Vec::new(),
            grid: GridStats::default(),
            lag_correlations: std::sync::OnceLock::new(),
            prefilter: false,
            fft,
            inv_dx: n as f64 / size_m,
        }
    }

    /// Whether the next [`Layer::compute_fields`] prefilters the fields for bilinear reads
    /// ([`super::Interp::Prefiltered`]): each wave's coefficient in the five derivative fields is
    /// divided by sqrt(T(theta_x) T(theta_z)), T = [`read_power_transfer`] of a bilinear read, so
    /// that the read keeps, on average over the positions between grid points, the wave's slope
    /// power; and in h, Dx and Dz multiplied by the gain with which the bilinear blend's own
    /// slope keeps it (see `Prefilter` in `fields.rs`). The grid's variance and mean square
    /// slope ([`GridStats`]) stay the sea's, from the coefficients before the gains.
    pub fn set_prefilter(&mut self, on: bool) {
        self.prefilter = on;
    }

    /// See [`Layer::set_prefilter`].
    pub fn prefilter(&self) -> bool {
        self.prefilter
    }

    pub fn size_m(&self) -> f64 {
        self.size_m
    }
    pub fn n(&self) -> usize {
        self.n
    }
    /// Grid spacing, m.
    pub fn dx(&self) -> f64 {
        self.size_m / self.n as f64
    }
    pub fn inv_dx(&self) -> f64 {
        self.inv_dx
    }
    /// The wavenumber band [k_min, k_max) this layer holds, rad/m.
    pub fn band(&self) -> (f64, f64) {
        (self.k_min, self.k_max)
    }
    pub fn choppiness(&self) -> f64 {
        self.choppiness
    }
    pub fn time_s(&self) -> f64 {
        self.time_s
    }
    /// The texels, z-major: texel (ix, iz) is `fields()[iz * n + ix]`.
    pub fn fields(&self) -> &[Texel] {
        &self.fields
    }
    /// Expected height variance of realizations with this layer's grid and band (sum of the
    /// cell integrals of P), m^2.
    pub fn expected_variance(&self) -> f64 {
        self.expected_variance
    }

    /// Mean of h^2 over the grid (= the variance over the period, by Parseval), m^2.
    pub fn height_variance(&self) -> f64 {
        self.grid.variance
    }

    /// h0 of grid cell (ix, iz), zero outside the band's reach.
    #[cfg(test)]
    pub(crate) fn h0_at(&self, ix: usize, iz: usize) -> C32 {
        let c = &self.cells;
        if c.inside(ix) && c.inside(iz) {
            self.h0[c.compact_index(ix) * c.width + c.compact_index(iz)]
        } else {
            C32::default()
        }
    }

    /// The grid indices (along either axis) of the cells the band can reach, ascending: h0 and
    /// h~ are zero at every cell with an index outside them.
    pub(crate) fn band_indices(&self) -> impl Iterator<Item = usize> + use<> {
        self.cells.grid_indices()
    }

    /// The band's reach m: the cells with |signed index| < m along both axes can hold energy.
    pub(crate) fn band_reach(&self) -> usize {
        self.cells.reach()
    }

    /// Means and bounds over the grid points (see [`GridStats`]).
    pub fn grid_stats(&self) -> &GridStats {
        &self.grid
    }

    /// Fraction of grid points where this layer alone folds (J <= 0), from its texels: for a
    /// prefiltered layer, of the prefiltered strains, which fold more often than the sea's
    /// (the summed surface's share, [`crate::ocean::Surface::folded_fraction`], is read between
    /// the grid points as a render reads it).
    pub fn folded_fraction(&self) -> f64 {
        let folded = self.fields.iter().filter(|t| jacobian(t) <= 0.0).count();
        folded as f64 / self.fields.len() as f64
    }

    /// Multiplies the amplitudes (and so every field) by `s`.
    pub fn scale(&mut self, s: f64) {
        let sf = s as f32;
        self.h0.par_iter_mut().for_each(|h| *h *= sf);
        self.fields
            .par_iter_mut()
            .for_each(|t| t.iter_mut().for_each(|v| *v *= sf));
        self.expected_variance *= s * s;
        let g = &mut self.grid;
        (g.variance, g.mss) = (g.variance * s * s, g.mss * s * s);
        g.max_strain = g.max_strain.map(|m| m * sf.abs());
    }
}

/// J = (1 + dDx/dx)(1 + dDz/dz) - (dDx/dz)^2 of one texel or sample.
#[inline]
pub fn jacobian(t: &Texel) -> f32 {
    (1.0 + t[field::DDX_DX]) * (1.0 + t[field::DDZ_DZ]) - t[field::DDX_DZ] * t[field::DDX_DZ]
}

#[cfg(test)]
mod read_tests;
#[cfg(test)]
mod tests;
