//! The random amplitudes h0(k) of one layer: each wavevector cell's share of the spectrum,
//! integrated over the cell, times a complex Gaussian.

use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::{C32, signed_index};
use crate::ocean::spectrum::{RadialTable, Spectrum};

/// Cells closer to k = 0 than this many fundamentals are integrated on at least an 8 x 8
/// sub-grid: there P (~ k^-3 on the tail) and the overlap weights change within a cell (one
/// midpoint under-counts a convex P by ~12 % at 2 fundamentals).
const SUBCELL_RADIUS: f64 = 8.0;

/// weight(|k|) P(k) as the cells integrate it: the spectrum's own formulas, or the radial
/// table (the fast path; see [`RadialTable`]).
pub(super) enum PointSpectrum<'a> {
    Exact {
        spectrum: &'a Spectrum,
        weight: &'a (dyn Fn(f64) -> f64 + Sync),
    },
    Table(RadialTable),
}

impl<'a> PointSpectrum<'a> {
    /// The table where the spectrum has one, else the exact formulas; `k_max` bounds the |k|
    /// the cells of a layer read.
    pub(super) fn new(
        spectrum: &'a Spectrum,
        weight: &'a (dyn Fn(f64) -> f64 + Sync),
        k_max: f64,
    ) -> PointSpectrum<'a> {
        match RadialTable::new(spectrum, weight, k_max) {
            Some(t) => PointSpectrum::Table(t),
            None => PointSpectrum::Exact { spectrum, weight },
        }
    }

    /// weight(|k|) P(kx, kz), |k| = `k` > 0.
    #[inline]
    fn p(&self, kx: f64, kz: f64, k: f64) -> f64 {
        match self {
            PointSpectrum::Exact { spectrum, weight } => {
                spectrum.p_k_at(kx, kz, k, spectrum.omega(k)) * weight(k)
            }
            PointSpectrum::Table(t) => t.p_k_at(kx, kz, k),
        }
    }

    /// The spreading's angular width at |k| = `k`.
    #[inline]
    fn width(&self, k: f64) -> f64 {
        match self {
            PointSpectrum::Exact { spectrum, .. } => spectrum.spreading_width(spectrum.omega(k)),
            PointSpectrum::Table(t) => t.spreading_width(k),
        }
    }
}

/// Integral of weight(|k|) P(-k) over the cell of side `dk` centred on (kx, kz) (h0(k) is drawn
/// from P(-k); see the module doc), on a sub-grid fine enough that each sub-cell spans at most
/// half the spreading's angular width (the paper's cases spread a few degrees, less than a cell
/// near the peak of a coarse-gridded layer) and 8 x 8 near k = 0.
fn cell_integral(p: &PointSpectrum, kx: f64, kz: f64, k: f64, dk: f64) -> f64 {
    let cell_angle = dk / k;
    let mut m = (2.0 * cell_angle / p.width(k)).ceil().clamp(1.0, 16.0) as usize;
    if k < SUBCELL_RADIUS * dk {
        m = m.max(8);
    }
    if m == 1 {
        return p.p(-kx, -kz, k) * dk * dk;
    }
    let sub = dk / m as f64;
    let centre = 0.5 * (m - 1) as f64;
    let mut sum = 0.0;
    for a in 0..m {
        for b in 0..m {
            let x = kx + (a as f64 - centre) * sub;
            let z = kz + (b as f64 - centre) * sub;
            let k = (x * x + z * z).sqrt();
            if k > 0.0 {
                sum += p.p(-x, -z, k);
            }
        }
    }
    sum * sub * sub
}

/// Two independent standard normals (Box-Muller).
fn gauss_pair(rng: &mut ChaCha8Rng) -> (f64, f64) {
    let u1 = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let u2 = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    // 1 - u1 is in (0, 1], so the log is finite
    let r = (-2.0 * (1.0 - u1).ln()).sqrt();
    let (s, c) = (TAU * u2).sin_cos();
    (r * c, r * s)
}

/// Words of the ChaCha8 stream one cell's [`gauss_pair`] reads (two `u64`).
const WORDS_PER_CELL: u128 = 4;

/// h0 for the cells of an `n` x `n` grid of spacing `dk` that can hold energy, in a
/// [`BandCells`] layout, zero outside `band` and at DC and the Nyquist row and column, and the
/// sum of the cell integrals (the expected height variance). Cell (ix, iz) draws its pair of
/// normals from words `4 iz` to `4 iz + 3` of ChaCha8 stream `ix` of `seed`, so the result
/// depends neither on the thread count nor on which cells are drawn: only cells with energy seek
/// to their words and draw (a coarse layer's band fills a fifth of its grid).
pub(super) fn draw(
    spectrum: &PointSpectrum,
    cells: &BandCells,
    dk: f64,
    band: (f64, f64),
    seed: u64,
) -> (Vec<C32>, f64) {
    let n = cells.n;
    let half = n / 2;
    let signed = move |i: usize| signed_index(i, n);
    let mut h0: Vec<C32> = bytemuck::zeroed_vec(cells.width * cells.width);
    let row_variance: Vec<f64> = h0
        .par_chunks_mut(cells.width)
        .enumerate()
        .map(|(cx, row)| {
            let ix = cells.grid_index(cx);
            let kx = signed(ix) * dk;
            // the Nyquist row pairs with itself; a row outside the band holds nothing
            if ix == half || kx.abs() >= band.1 {
                return 0.0;
            }
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(ix as u64);
            let mut var = 0.0;
            // in the order of the stream's words, so seeks are rare
            for iz in cells.grid_indices() {
                // the Nyquist column pairs with itself; DC has no direction
                if iz == half || (ix == 0 && iz == 0) {
                    continue;
                }
                let kz = signed(iz) * dk;
                let k = (kx * kx + kz * kz).sqrt();
                if !(k >= band.0 && k < band.1) {
                    continue;
                }
                let cell = cell_integral(spectrum, kx, kz, k, dk);
                if cell > 0.0 {
                    let at = WORDS_PER_CELL * iz as u128;
                    // a seek refills ChaCha's block buffer: only where the previous cell was skipped
                    if rng.get_word_pos() != at {
                        rng.set_word_pos(at);
                    }
                    let (g1, g2) = gauss_pair(&mut rng);
                    // E|h0|^2 = P dk^2 / 2, so the sum of E|h~(k)|^2 over k is the variance
                    let a = 0.5 * cell.sqrt();
                    row[cells.compact_index(iz)] = C32::new((a * g1) as f32, (a * g2) as f32);
                    var += cell;
                }
            }
            var
        })
        .collect();
    (h0, row_variance.iter().sum())
}

/// The cells of an `n` x `n` grid that a band below `k_max` can reach: signed indices
/// -m < s < m along each axis, with m dk >= k_max, stored as a `width` x `width` square
/// (width = 2m - 1; s >= 0 at s, s < 0 at width + s). A coarse layer's band reaches half its
/// Nyquist, so its amplitudes take a quarter of the grid.
#[derive(Clone, Copy, Debug)]
pub(super) struct BandCells {
    pub n: usize,
    /// m: every cell in the band has |signed index| < m along both axes.
    reach: usize,
    pub width: usize,
}

impl BandCells {
    pub fn new(n: usize, dk: f64, k_max: f64) -> BandCells {
        // floor + 1, not ceil: a cell s with s dk < k_max is kept even where k_max / dk rounds
        // down to s (an integer ratio keeps one spare row and column of zeros)
        let reach = ((k_max / dk).floor() as usize + 1).clamp(1, n / 2);
        BandCells {
            n,
            reach,
            width: 2 * reach - 1,
        }
    }

    /// m: every signed index s with |s| < m (along either axis) is within the reach.
    #[inline]
    pub fn reach(&self) -> usize {
        self.reach
    }

    /// The compact index of grid index `i`, which must be inside (see [`BandCells::inside`]).
    #[inline]
    pub fn compact_index(&self, i: usize) -> usize {
        if i < self.reach {
            i
        } else {
            i + self.width - self.n
        }
    }

    /// Whether grid index `i` (0..n) is within the reach.
    #[inline]
    pub fn inside(&self, i: usize) -> bool {
        i < self.reach || i > self.n - self.reach
    }

    /// The grid index of compact index `c`.
    #[inline]
    pub fn grid_index(&self, c: usize) -> usize {
        if c < self.reach {
            c
        } else {
            c + self.n - self.width
        }
    }

    /// The grid indices outside the reach: one run between the two ends of the grid.
    #[inline]
    pub fn outside(&self) -> std::ops::Range<usize> {
        self.reach..self.n - self.reach + 1
    }

    /// The grid indices within the reach, ascending.
    pub fn grid_indices(&self) -> impl Iterator<Item = usize> + use<> {
        let (reach, n) = (self.reach, self.n);
        (0..reach).chain(n - reach + 1..n)
    }
}
