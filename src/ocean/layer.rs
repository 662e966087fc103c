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

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use super::spectrum::Spectrum;
use super::{Interp, OceanError};
use crate::config::ocean::{MAX_N, MIN_N};
use crate::rng::splitmix64;

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

/// Cells closer to k = 0 than this many fundamentals are integrated on at least an 8 x 8
/// sub-grid: there P (~ k^-3 on the tail) and the overlap weights change within a cell (one
/// midpoint under-counts a convex P by ~12 % at 2 fundamentals).
const SUBCELL_RADIUS: f64 = 8.0;

/// Integral of weight(|k|) P(-k) over the cell of side `dk` centred on (kx, kz) (h0(k) is drawn
/// from P(-k); see the module doc), on a sub-grid fine enough that each sub-cell spans at most
/// half the spreading's angular width (the paper's cases spread a few degrees, less than a cell
/// near the peak of a coarse-gridded layer) and 8 x 8 near k = 0.
fn cell_integral(
    spectrum: &Spectrum,
    weight: &(dyn Fn(f64) -> f64 + Sync),
    kx: f64,
    kz: f64,
    dk: f64,
) -> f64 {
    let k = kx.hypot(kz);
    let cell_angle = dk / k;
    let width = spectrum.spreading_width(spectrum.omega(k));
    let mut m = (2.0 * cell_angle / width).ceil().clamp(1.0, 16.0) as usize;
    if k < SUBCELL_RADIUS * dk {
        m = m.max(8);
    }
    if m == 1 {
        return spectrum.p_k(-kx, -kz) * dk * dk * weight(k);
    }
    let sub = dk / m as f64;
    let centre = 0.5 * (m - 1) as f64;
    let mut sum = 0.0;
    for a in 0..m {
        for b in 0..m {
            let x = kx + (a as f64 - centre) * sub;
            let z = kz + (b as f64 - centre) * sub;
            sum += spectrum.p_k(-x, -z) * weight(x.hypot(z));
        }
    }
    sum * sub * sub
}

/// One periodic realization: amplitudes, dispersion and the gridded fields at one time.
pub struct Layer {
    size_m: f64,
    n: usize,
    k_min: f64,
    k_max: f64,
    choppiness: f64,
    time_s: f64,
    /// h0(k), kx-major (index ix * n + iz), zero outside the band.
    h0: Vec<C32>,
    /// Water depth for the dispersion relation: omega(|k|) is computed where h0 is non-zero
    /// rather than stored (64 MB for a 2048-texel layer).
    depth_m: f64,
    expected_variance: f64,
    /// Texels, z-major (index iz * n + ix); texel (ix, iz) is at (ix L/n, iz L/n).
    fields: Vec<Texel>,
    fft: Arc<dyn Fft<f32>>,
    inv_dx: f64,
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

/// Grid coordinates of smaller magnitude split in `i32` lanes; a point beyond (2^30 texels out,
/// 25 000 km for the finest default layer) takes the scalar [`split`].
const LANE_RANGE: f64 = (1u32 << 30) as f64;

/// [`split`] for lanes of grid coordinates within `LANE_RANGE`, in vector code. Adding
/// 1.5 x 2^52 rounds a coordinate to the nearest integer, whose two's complement is then the
/// low 32 bits of the sum (exact below 2^51); one less where that rounded up is the floor.
/// (A float-to-int cast would be scalar code: Rust's `as` saturates.)
#[inline]
fn split_lanes<const LANES: usize>(p: &[f64; LANES]) -> ([i32; LANES], [f32; LANES]) {
    const ROUND: f64 = 6_755_399_441_055_744.0; // 1.5 x 2^52
    let mut i = [0i32; LANES];
    let mut f = [0.0f32; LANES];
    for l in 0..LANES {
        let shifted = p[l] + ROUND;
        let nearest = shifted - ROUND;
        let up = nearest > p[l];
        let floor = if up { nearest - 1.0 } else { nearest };
        i[l] = (shifted.to_bits() as i32).wrapping_sub(i32::from(up));
        f[l] = (p[l] - floor) as f32;
    }
    (i, f)
}

/// The weights of texels (ix, iz), (ix+1, iz), (ix, iz+1), (ix+1, iz+1) at fractions (fx, fz).
#[inline]
fn bilinear_weights(fx: f32, fz: f32) -> [f32; 4] {
    let (gx, gz) = (1.0 - fx, 1.0 - fz);
    [gx * gz, fx * gz, gx * fz, fx * fz]
}

/// `sum += t`, field by field.
#[inline]
pub(crate) fn add_texel(sum: &mut Texel, t: &Texel) {
    for (s, t) in sum.iter_mut().zip(t) {
        *s += t;
    }
}

/// The weighted sum of four texels, field by field.
#[inline]
fn blend(t: [&Texel; 4], w: [f32; 4]) -> Texel {
    let mut r = [0.0f32; FIELD_COUNT];
    for j in 0..FIELD_COUNT {
        r[j] = w[0] * t[0][j] + w[1] * t[1][j] + w[2] * t[2][j] + w[3] * t[3][j];
    }
    r
}

#[inline]
fn split(p: f64) -> (i64, f32) {
    // truncation plus correction: floor() is a libm call on baseline x86-64
    let i = p as i64;
    let i = if (i as f64) > p { i - 1 } else { i };
    (i, (p - i as f64) as f32)
}

#[inline]
fn catmull_rom(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// FFT bin `i` of `n` as a signed frequency index: 0..n/2 stay, the upper half wraps negative.
#[inline]
fn signed_index(i: usize, n: usize) -> f64 {
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
        let half = n / 2;
        let signed = move |i: usize| signed_index(i, n);
        let seed = splitmix64(seed);
        let rows: Vec<(Vec<C32>, f64)> = (0..n)
            .into_par_iter()
            .map(|ix| {
                // one stream per row keeps the draw independent of scheduling
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(ix as u64);
                let kx = signed(ix) * dk;
                let mut h0 = vec![C32::default(); n];
                let mut var = 0.0;
                for (iz, slot) in h0.iter_mut().enumerate() {
                    let (g1, g2) = gauss_pair(&mut rng);
                    let kz = signed(iz) * dk;
                    let k = kx.hypot(kz);
                    // the Nyquist row and column pair with themselves; DC has no direction
                    if ix == half || iz == half || (ix == 0 && iz == 0) {
                        continue;
                    }
                    if !(k >= band.0 && k < band.1) {
                        continue;
                    }
                    let cell = cell_integral(spectrum, weight, kx, kz, dk);
                    if cell > 0.0 {
                        // E|h0|^2 = P dk^2 / 2, so the sum of E|h~(k)|^2 over k is the variance
                        let a = 0.5 * cell.sqrt();
                        *slot = C32::new((a * g1) as f32, (a * g2) as f32);
                        var += cell;
                    }
                }
                (h0, var)
            })
            .collect();
        let mut h0 = Vec::with_capacity(n * n);
        let mut expected_variance = 0.0;
        for (h, v) in rows {
            h0.extend_from_slice(&h);
            expected_variance += v;
        }
        let fft = FftPlanner::<f32>::new().plan_fft_inverse(n);
        let mut layer = Layer {
            size_m,
            n,
            k_min: band.0,
            k_max: band.1,
            choppiness,
            time_s,
            h0,
            depth_m: spectrum.depth_m,
            expected_variance,
            fields: vec![[0.0; FIELD_COUNT]; n * n],
            fft,
            inv_dx: n as f64 / size_m,
        };
        layer.compute_fields(time_s);
        Ok(layer)
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
        let s: f64 = self
            .fields
            .iter()
            .map(|t| (t[field::H] as f64).powi(2))
            .sum();
        s / self.fields.len() as f64
    }

    /// Fraction of grid points where this layer alone folds (J <= 0).
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
    }

    /// h~(k, t) of eq. 2 for cell `i` (kx-major) in f64.
    #[inline]
    fn h_tilde(&self, ix: usize, iz: usize, t: f64) -> Complex<f64> {
        let n = self.n;
        let i = ix * n + iz;
        let a = self.h0[i];
        let b = self.h0[((n - ix) & (n - 1)) * n + ((n - iz) & (n - 1))];
        if a == C32::default() && b == C32::default() {
            return Complex::default();
        }
        let dk = TAU / self.size_m;
        let k = (signed_index(ix, n) * dk).hypot(signed_index(iz, n) * dk);
        let omega = super::spectrum::dispersion(k, self.depth_m);
        let (s, c) = (omega * t).rem_euclid(TAU).sin_cos();
        let e = Complex::new(c, s);
        let a = Complex::new(a.re as f64, a.im as f64);
        let b = Complex::new(b.re as f64, -(b.im as f64));
        a * e + b * e.conj()
    }

    /// Recomputes the eight fields at time `t` (eq. 2, then four packed 2-D inverse FFTs).
    pub fn compute_fields(&mut self, t: f64) {
        let n = self.n;
        self.time_s = t;
        let dk = TAU / self.size_m;
        let signed = move |i: usize| signed_index(i, n);
        let lam = self.choppiness;
        let mut ht = vec![C32::default(); n * n];
        ht.par_chunks_mut(n).enumerate().for_each(|(ix, row)| {
            for (iz, out) in row.iter_mut().enumerate() {
                let h = self.h_tilde(ix, iz, t);
                *out = C32::new(h.re as f32, h.im as f32);
            }
        });
        // A_j = F_{2j} + i F_{2j+1} = h~ m_j(k) for the field pairs (h, Dx), (Dz, dh/dx),
        // (dh/dz, dDx/dx), (dDz/dz, dDx/dz), with D~ = i lambda k/|k| h~ and d/dx -> i kx.
        let multiplier = |j: usize, kx: f64, kz: f64| -> C32 {
            let k = kx.hypot(kz);
            let (ux, uz) = if k > 0.0 {
                (kx / k, kz / k)
            } else {
                (0.0, 0.0)
            };
            let m = match j {
                0 => Complex::new(1.0 - lam * ux, 0.0),
                1 => Complex::new(-kx, lam * uz),
                2 => Complex::new(0.0, kz - lam * kx * ux),
                _ => Complex::new(-lam * kz * uz, -lam * kx * uz),
            };
            C32::new(m.re as f32, m.im as f32)
        };
        let mut a = vec![C32::default(); n * n];
        let mut b = vec![C32::default(); n * n];
        for j in 0..4 {
            a.par_chunks_mut(n)
                .zip(ht.par_chunks(n))
                .enumerate()
                .for_each(|(ix, (row, hrow))| {
                    let kx = signed(ix) * dk;
                    for (iz, (out, h)) in row.iter_mut().zip(hrow).enumerate() {
                        *out = if *h == C32::default() {
                            C32::default()
                        } else {
                            *h * multiplier(j, kx, signed(iz) * dk)
                        };
                    }
                });
            // a: [kx][kz] -> [kx][z]; b = transpose: [z][kx] -> [z][x]
            self.fft_rows(&mut a);
            transpose(&a, &mut b, n);
            self.fft_rows(&mut b);
            self.fields
                .par_chunks_mut(n)
                .zip(b.par_chunks(n))
                .for_each(|(out, src)| {
                    for (t, v) in out.iter_mut().zip(src) {
                        t[2 * j] = v.re;
                        t[2 * j + 1] = v.im;
                    }
                });
        }
    }

    fn fft_rows(&self, buf: &mut [C32]) {
        let n = self.n;
        let rows_per_task = (4096 / n).max(1);
        let scratch_len = self.fft.get_inplace_scratch_len();
        buf.par_chunks_mut(n * rows_per_task).for_each_init(
            || vec![C32::default(); scratch_len],
            |scratch, chunk| self.fft.process_with_scratch(chunk, scratch),
        );
    }

    /// The complex inverse FFT of h~ alone, z-major; its imaginary part measures how real h is.
    #[cfg(test)]
    pub(crate) fn height_complex(&self) -> Vec<C32> {
        let n = self.n;
        let mut a = vec![C32::default(); n * n];
        for ix in 0..n {
            for iz in 0..n {
                let h = self.h_tilde(ix, iz, self.time_s);
                a[ix * n + iz] = C32::new(h.re as f32, h.im as f32);
            }
        }
        let mut b = vec![C32::default(); n * n];
        self.fft_rows(&mut a);
        transpose(&a, &mut b, n);
        self.fft_rows(&mut b);
        b
    }

    #[inline]
    fn texel(&self, ix: i64, iz: i64) -> &Texel {
        let m = (self.n - 1) as i64;
        &self.fields[(iz & m) as usize * self.n + (ix & m) as usize]
    }

    /// Bilinear read at grid coordinates (px, pz) = position / dx, any value (wraps).
    #[inline]
    pub fn bilinear(&self, px: f64, pz: f64) -> Texel {
        let (ix, fx) = split(px);
        let (iz, fz) = split(pz);
        let (t00, t10) = (self.texel(ix, iz), self.texel(ix + 1, iz));
        let (t01, t11) = (self.texel(ix, iz + 1), self.texel(ix + 1, iz + 1));
        blend([t00, t10, t01, t11], bilinear_weights(fx, fz))
    }

    /// Adds the bilinear reads at the grid coordinates `(px[l], pz[l])` of the first `count`
    /// lanes into `sum[l]`, bit for bit `sum[l] += self.bilinear(px[l], pz[l])`. The lanes'
    /// cells and weights are computed together (vector code, where `bilinear` spends most of
    /// its instructions one point at a time); each lane then reads its four texels. Lanes past
    /// `count` are computed and not read, whatever they hold.
    #[inline]
    pub fn add_bilinear_lanes<const LANES: usize>(
        &self,
        px: &[f64; LANES],
        pz: &[f64; LANES],
        count: usize,
        sum: &mut [Texel; LANES],
    ) {
        debug_assert!(count <= LANES);
        // All lanes, without a branch (one past `count` out of range costs time, not bits).
        let in_range = px.iter().zip(pz).fold(true, |ok, (x, z)| {
            ok & (x.abs() < LANE_RANGE) & (z.abs() < LANE_RANGE)
        });
        if !in_range {
            // Far out (or NaN): the scalar read, whose split takes any coordinate.
            for l in 0..count {
                add_texel(&mut sum[l], &self.bilinear(px[l], pz[l]));
            }
            return;
        }
        let (ix, fx) = split_lanes(px);
        let (iz, fz) = split_lanes(pz);
        let m = (self.n - 1) as i32;
        let shift = self.n.trailing_zeros();
        // Per corner, per lane (the layout vector code wants).
        let mut cells = [[0u32; LANES]; 4];
        let mut weights = [[0.0f32; LANES]; 4];
        for l in 0..LANES {
            let (x0, x1) = (ix[l] & m, (ix[l] + 1) & m);
            let (z0, z1) = ((iz[l] & m) << shift, ((iz[l] + 1) & m) << shift);
            for (c, i) in [z0 | x0, z0 | x1, z1 | x0, z1 | x1].into_iter().enumerate() {
                cells[c][l] = i as u32;
            }
            for (c, w) in bilinear_weights(fx[l], fz[l]).into_iter().enumerate() {
                weights[c][l] = w;
            }
        }
        // Masking a cell (below n^2, a power of two) changes nothing but spares the bounds
        // check: the compiler knows i & (len - 1) < len.
        let f = &self.fields[..];
        let mask = f.len() - 1;
        for (l, s) in sum.iter_mut().enumerate().take(count) {
            let t = blend(
                std::array::from_fn(|c| &f[cells[c][l] as usize & mask]),
                std::array::from_fn(|c| weights[c][l]),
            );
            add_texel(s, &t);
        }
    }

    /// Catmull-Rom bicubic read at grid coordinates (px, pz) (wraps).
    #[inline]
    pub fn bicubic(&self, px: f64, pz: f64) -> Texel {
        let (ix, fx) = split(px);
        let (iz, fz) = split(pz);
        let (wx, wz) = (catmull_rom(fx), catmull_rom(fz));
        let mut r = [0.0f32; FIELD_COUNT];
        for (dz, wzv) in wz.iter().enumerate() {
            let mut row = [0.0f32; FIELD_COUNT];
            for (dx, wxv) in wx.iter().enumerate() {
                let t = self.texel(ix - 1 + dx as i64, iz - 1 + dz as i64);
                for j in 0..FIELD_COUNT {
                    row[j] += wxv * t[j];
                }
            }
            for j in 0..FIELD_COUNT {
                r[j] += wzv * row[j];
            }
        }
        r
    }

    /// Read at grid coordinates with the chosen interpolation.
    #[inline]
    pub fn read(&self, px: f64, pz: f64, interp: Interp) -> Texel {
        match interp {
            Interp::Bilinear => self.bilinear(px, pz),
            Interp::Bicubic => self.bicubic(px, pz),
        }
    }

    /// The eight fields at (x, z) metres by summing the Fourier series directly (O(n^2), f64):
    /// the exact band-limited field the grid samples.
    pub fn eval_direct(&self, x: f64, z: f64) -> [f64; FIELD_COUNT] {
        let n = self.n;
        let dk = TAU / self.size_m;
        let signed = |i: usize| signed_index(i, n);
        let lam = self.choppiness;
        let mut v = [0.0f64; FIELD_COUNT];
        for ix in 0..n {
            let kx = signed(ix) * dk;
            for iz in 0..n {
                let h = self.h_tilde(ix, iz, self.time_s);
                if h == Complex::default() {
                    continue;
                }
                let kz = signed(iz) * dk;
                let k = kx.hypot(kz);
                let (ux, uz) = (kx / k, kz / k);
                // the phase is reduced per axis so that x + L gives the same bits
                let ph = (signed(ix) * (x / self.size_m)).rem_euclid(1.0)
                    + (signed(iz) * (z / self.size_m)).rem_euclid(1.0);
                let q = h * Complex::from_polar(1.0, TAU * ph);
                v[field::H] += q.re;
                v[field::DX] -= lam * ux * q.im;
                v[field::DZ] -= lam * uz * q.im;
                v[field::DH_DX] -= kx * q.im;
                v[field::DH_DZ] -= kz * q.im;
                v[field::DDX_DX] -= lam * kx * ux * q.re;
                v[field::DDZ_DZ] -= lam * kz * uz * q.re;
                v[field::DDX_DZ] -= lam * kx * uz * q.re;
            }
        }
        v
    }
}

/// J = (1 + dDx/dx)(1 + dDz/dz) - (dDx/dz)^2 of one texel or sample.
#[inline]
pub fn jacobian(t: &Texel) -> f32 {
    (1.0 + t[field::DDX_DX]) * (1.0 + t[field::DDZ_DZ]) - t[field::DDX_DZ] * t[field::DDX_DZ]
}

/// Out-of-place transpose of an n x n matrix in row blocks, so reads stay in short runs.
fn transpose(src: &[C32], dst: &mut [C32], n: usize) {
    const B: usize = 16;
    dst.par_chunks_mut(n * B)
        .enumerate()
        .for_each(|(blk, chunk)| {
            let r0 = blk * B;
            let rows = chunk.len() / n;
            for c in 0..n {
                let s = &src[c * n + r0..c * n + r0 + rows];
                for (dr, v) in s.iter().enumerate() {
                    chunk[dr * n + c] = *v;
                }
            }
        });
}

#[cfg(test)]
#[path = "layer_tests.rs"]
mod tests;
