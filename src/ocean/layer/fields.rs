//! The eight fields of a layer at one time: h~(k, t) of eq. 2 times each field's spectral
//! multiplier, two real fields per complex 2-D inverse FFT.

use std::f64::consts::TAU;

use rayon::prelude::*;
use rustfft::num_complex::Complex;

use super::{C32, FIELD_COUNT, GridStats, Layer, read_power_transfer, signed_index};
use crate::ocean::Interp;

impl Layer {
    /// h~(k, t) of eq. 2 for cell (`ix`, `iz`) in f64.
    #[inline]
    pub(crate) fn h_tilde(&self, ix: usize, iz: usize, t: f64) -> Complex<f64> {
        self.h_tilde_row(ix, t)(iz)
    }

    /// [`Layer::h_tilde`] along row `ix`, with the row's look-ups done once: the loops over a
    /// layer's cells (its fields, its Parseval variance, its slope tables) call it a million
    /// times a big layer, and the per-cell index arithmetic was most of its cost.
    #[inline]
    pub(crate) fn h_tilde_row(&self, ix: usize, t: f64) -> impl Fn(usize) -> Complex<f64> + '_ {
        let pairs = self.h0_pair_row(ix);
        let phase = self.phase_row(ix, t);
        move |iz: usize| match pairs(iz) {
            Some((a, b)) => h_tilde_of(a, b, phase(iz)),
            None => Complex::default(),
        }
    }

    /// The amplitudes h~(k, t) of row `ix` combines, cell by cell ([`h_tilde_of`]): h0(k) and
    /// h0(-k), or `None` where both are zero (outside the band's reach, or no energy).
    #[inline]
    pub(crate) fn h0_pair_row(&self, ix: usize) -> impl Fn(usize) -> Option<(C32, C32)> + '_ {
        let (n, c) = (self.n, &self.cells);
        // the mirror -k of a cell within the band's reach is within it too
        let rows = c.inside(ix).then(|| {
            let row = |i: usize| &self.h0[c.compact_index(i) * c.width..][..c.width];
            (row(ix), row((n - ix) & (n - 1)))
        });
        move |iz: usize| {
            let (ra, rb) = rows.filter(|_| c.inside(iz))?;
            let a = ra[c.compact_index(iz)];
            let b = rb[c.compact_index((n - iz) & (n - 1))];
            (a != C32::default() || b != C32::default()).then_some((a, b))
        }
    }

    /// e^(i omega t) for the cells of row `ix` (omega by the dispersion relation at this
    /// layer's depth); at t = 0 exactly 1 (what sin_cos(0) gives), the time of every still
    /// render: the dispersion relation's tanh and the sine and cosine were 5 % of its build.
    #[inline]
    pub(crate) fn phase_row(&self, ix: usize, t: f64) -> impl Fn(usize) -> Complex<f64> + use<> {
        let (n, depth_m) = (self.n, self.depth_m);
        let dk = TAU / self.size_m;
        let kx = signed_index(ix, n) * dk;
        move |iz: usize| {
            if t == 0.0 {
                Complex::new(1.0, 0.0)
            } else {
                let k = kx.hypot(signed_index(iz, n) * dk);
                let omega = crate::ocean::spectrum::dispersion(k, depth_m);
                let (s, c) = (omega * t).rem_euclid(TAU).sin_cos();
                Complex::new(c, s)
            }
        }
    }

    /// The variance of h over the grid at time `t` from the amplitudes alone: by Parseval the
    /// sum of |h~(k, t)|^2 over the cells (h is real), what [`Layer::height_variance`] measures
    /// once the fields are computed, to f32 rounding.
    pub fn spectral_height_variance(&self, t: f64) -> f64 {
        let rows: Vec<f64> = self
            .band_rows()
            .into_par_iter()
            .map(|ix| {
                let h = self.h_tilde_row(ix, t);
                self.cells.grid_indices().map(|iz| h(iz).norm_sqr()).sum()
            })
            .collect();
        rows.iter().sum()
    }

    /// The kx rows that can hold a non-zero h~: |kx| < k_max (h0 is zero outside the band and
    /// at Nyquist).
    fn band_rows(&self) -> Vec<usize> {
        let (n, dk) = (self.n, TAU / self.size_m);
        (0..n)
            .filter(|&ix| ix != n / 2 && signed_index(ix, n).abs() * dk < self.k_max)
            .collect()
    }

    /// Recomputes the eight fields at time `t` (eq. 2, then four packed 2-D inverse FFTs).
    pub fn compute_fields(&mut self, t: f64) {
        self.compute_fields_in(t, &mut FieldPlanes::default());
    }

    /// [`Layer::compute_fields`] with the transforms' intermediate planes in `planes`, which
    /// grow to the largest layer they serve: a surface computes its layers one after another
    /// in the same planes (a 2048-texel layer's are 67 MB, and zeroing fresh memory took a
    /// third of its fields' time).
    ///
    /// Four planes A_j = F_{2j} + i F_{2j+1} = h~ m_j(k) hold the field pairs (h, Dx),
    /// (Dz, dh/dx), (dh/dz, dDx/dx), (dDz/dz, dDx/dz), with D~ = i lambda k/|k| h~ and
    /// d/dx -> i kx. The planes keep only the kx rows inside the band (a coarse layer's band
    /// reaches half its Nyquist: half the rows). Each row is filled and transformed along kz
    /// while it is in cache (h~ and the multipliers once per cell for all four planes). Then
    /// blocks of z columns are gathered from the rows, zero outside them, transformed along kx
    /// and written into their texels once, all eight fields together.
    pub fn compute_fields_in(&mut self, t: f64, planes: &mut FieldPlanes) {
        let n = self.n;
        self.time_s = t;
        self.lag_correlations = std::sync::OnceLock::new();
        let dk = TAU / self.size_m;
        let signed = move |i: usize| signed_index(i, n);
        let lam = self.choppiness;
        let scratch_len = self.fft.get_inplace_scratch_len();
        if self.fields.len() != n * n {
            self.fields = vec![[0.0; FIELD_COUNT]; n * n];
            crate::memory::prefault(&mut self.fields);
        }
        let rows = self.band_rows();
        let prefilter = self.prefilter.then(|| Prefilter::new(n));
        let prefilter = prefilter.as_ref();
        for p in &mut planes.0 {
            // fresh zero pages (calloc), mapped in on every core in one call each: zeroing them
            // here on one thread cost a 2048-texel layer a third of its time, and a fault per
            // page on first write 11 % of the ocean's processor time
            if p.len() < rows.len() * n {
                *p = bytemuck::zeroed_vec(rows.len() * n);
                crate::memory::prefault(p);
            }
            p.truncate(rows.len() * n);
        }
        // the sea's variance and mean square slope by Parseval, before any prefilter
        let sea: [f64; 2] = {
            let this = &*self;
            let [p0, p1, p2, p3] = &mut planes.0;
            p0.par_chunks_mut(n)
                .zip(p1.par_chunks_mut(n))
                .zip(p2.par_chunks_mut(n))
                .zip(p3.par_chunks_mut(n))
                .zip(rows.par_iter())
                .map_init(
                    || vec![C32::default(); scratch_len],
                    |scratch, ((((r0, r1), r2), r3), &ix)| {
                        let kx = signed(ix) * dk;
                        let mut rows = [r0, r1, r2, r3];
                        // the cells outside the band's reach are zero, and each cell inside is
                        // written once below (the planes hold the previous layer's rows)
                        let outside = this.cells.outside();
                        for row in rows.iter_mut() {
                            row[outside.clone()].fill(C32::default());
                        }
                        let mut any = false;
                        let mut sea = [0.0f64; 2];
                        let h_tilde = this.h_tilde_row(ix, t);
                        for iz in this.cells.grid_indices() {
                            let h = h_tilde(iz);
                            if h == Complex::default() {
                                for row in rows.iter_mut() {
                                    row[iz] = C32::default();
                                }
                                continue;
                            }
                            any = true;
                            let kz = signed(iz) * dk;
                            let h = C32::new(h.re as f32, h.im as f32);
                            let mut m = multipliers(lam, kx, kz);
                            if let Some(p) = prefilter {
                                let power = h.norm_sqr() as f64;
                                sea[0] += power;
                                sea[1] += power * (kx * kx + kz * kz);
                                p.apply(&mut m, ix, iz);
                            }
                            for j in 0..4 {
                                rows[j][iz] = h * m[j];
                            }
                        }
                        if any {
                            for row in rows {
                                this.fft.process_with_scratch(row, scratch);
                            }
                        }
                        sea
                    },
                )
                .reduce(|| [0.0; 2], |a, b| [a[0] + b[0], a[1] + b[1]])
        };
        // Blocks of COLUMNS z rows: gathered over kx (runs of COLUMNS values per stored row),
        // transformed along kx, and each texel written once, measured as it is written.
        const COLUMNS: usize = 16;
        let fft = &self.fft;
        // the kx rows outside the band, zero in every gathered column
        let gaps: Vec<std::ops::Range<usize>> = (0..=rows.len())
            .map(|r| {
                let start = if r == 0 { 0 } else { rows[r - 1] + 1 };
                start..rows.get(r).copied().unwrap_or(n)
            })
            .filter(|g| !g.is_empty())
            .collect();
        let (planes, rows, gaps) = (&planes.0, &rows, &gaps);
        let blocks: Vec<GridStats> = self
            .fields
            .par_chunks_mut(n * COLUMNS)
            .enumerate()
            .map_init(
                || {
                    let buf: [Vec<C32>; 4] =
                        std::array::from_fn(|_| vec![C32::default(); COLUMNS * n]);
                    (buf, vec![C32::default(); scratch_len])
                },
                |(buf, scratch), (block, out)| {
                    let z0 = block * COLUMNS;
                    let width = out.len() / n;
                    for (plane, b) in planes.iter().zip(buf.iter_mut()) {
                        let b = &mut b[..width * n];
                        // (the band rows are all written below)
                        for column in b.chunks_exact_mut(n) {
                            for gap in gaps {
                                column[gap.clone()].fill(C32::default());
                            }
                        }
                        // eight band rows at a time, so that each column's cache line is
                        // written whole, not one value per row (the columns lie n apart, and
                        // sixteen lines that far apart share a set of the L1 cache)
                        for (r8, ixs) in rows.chunks(8).enumerate() {
                            let r0 = r8 * 8;
                            for dz in 0..width {
                                let column = &mut b[dz * n..(dz + 1) * n];
                                for (t, &ix) in ixs.iter().enumerate() {
                                    column[ix] = plane[(r0 + t) * n + z0 + dz];
                                }
                            }
                        }
                        fft.process_with_scratch(b, scratch);
                    }
                    let mut stats = GridStats::default();
                    for (dz, texels) in out.chunks_mut(n).enumerate() {
                        for (x, texel) in texels.iter_mut().enumerate() {
                            for j in 0..4 {
                                let v = buf[j][dz * n + x];
                                texel[2 * j] = v.re;
                                texel[2 * j + 1] = v.im;
                            }
                            stats.add(texel);
                        }
                    }
                    stats
                },
            )
            .collect();
        let mut grid = blocks.iter().fold(GridStats::default(), |a, b| a.merge(b));
        grid.variance /= (n * n) as f64;
        grid.mss /= (n * n) as f64;
        if self.prefilter {
            [grid.variance, grid.mss] = sea;
        }
        self.grid = grid;
    }

    #[cfg(test)]
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
}

/// The four intermediate planes of [`Layer::compute_fields_in`], kept between layers.
#[derive(Default)]
pub struct FieldPlanes([Vec<C32>; 4]);

/// h~(k, t) of eq. 2 from h0(k) = `a`, h0(-k) = `b` and e^(i omega t) = `e`:
/// a e + conj(b) conj(e), in f64.
#[inline]
pub(crate) fn h_tilde_of(a: C32, b: C32, e: Complex<f64>) -> Complex<f64> {
    let a = Complex::new(a.re as f64, a.im as f64);
    let b = Complex::new(b.re as f64, -(b.im as f64));
    a * e + b * e.conj()
}

/// The spectral multipliers m_j(k) of [`Layer::compute_fields`]'s four planes.
#[inline]
pub(super) fn multipliers(lam: f64, kx: f64, kz: f64) -> [C32; 4] {
    // (not hypot: no overflow or underflow to guard against at these wavenumbers, and glibc's
    // hypot was 3 % of the ocean's build; the multipliers are rounded to f32)
    let k = (kx * kx + kz * kz).sqrt();
    let (ux, uz) = if k > 0.0 {
        (kx / k, kz / k)
    } else {
        (0.0, 0.0)
    };
    [
        Complex::new(1.0 - lam * ux, 0.0),
        Complex::new(-kx, lam * uz),
        Complex::new(0.0, kz - lam * kx * ux),
        Complex::new(-lam * kz * uz, -lam * kx * uz),
    ]
    .map(|m| C32::new(m.re as f32, m.im as f32))
}

/// The gains of [`super::Interp::Prefiltered`] ([`Layer::set_prefilter`]), from each axis's
/// phase step theta = 2 pi s / n of a wave of signed index s: what a bilinear read keeps of its
/// power, T = (2 + cos theta) / 3, and what the difference across a cell keeps of its slope's,
/// S = sinc^2(theta / 2).
struct Prefilter {
    theta: Vec<f64>,
    read: Vec<f64>,
    difference: Vec<f64>,
}

impl Prefilter {
    fn new(n: usize) -> Prefilter {
        let theta: Vec<f64> = (0..n)
            .map(|i| TAU * signed_index(i, n) / n as f64)
            .collect();
        let read = theta
            .iter()
            .map(|&t| read_power_transfer(Interp::Bilinear, t))
            .collect();
        let difference = theta
            .iter()
            .map(|&t| {
                let x = 0.5 * t;
                if x == 0.0 { 1.0 } else { (x.sin() / x).powi(2) }
            })
            .collect();
        Prefilter {
            theta,
            read,
            difference,
        }
    }

    /// Scales [`multipliers`]' planes for cell (ix, iz), each by a real gain even in k (so each
    /// plane's pair of fields stays a pair of real fields). The five derivative fields, read
    /// bilinearly by the normals, by 1 / sqrt(T_x T_z): the read keeps the wave's power. h, Dx
    /// and Dz, whose bilinear blend is the surface the mesh and the exact intersector place,
    /// by the gain g with which that blend's own slope keeps the wave's slope power,
    /// g^2 (theta_x^2 S_x T_z + theta_z^2 T_x S_z) = theta_x^2 + theta_z^2 (the blend's x slope is
    /// the difference across the cell blended along z, and the other way round).
    #[inline]
    fn apply(&self, m: &mut [C32; 4], ix: usize, iz: usize) {
        let read = (1.0 / (self.read[ix] * self.read[iz]).sqrt()) as f32;
        let (tx, tz) = (self.theta[ix], self.theta[iz]);
        let slope = tx * tx * self.difference[ix] * self.read[iz]
            + tz * tz * self.read[ix] * self.difference[iz];
        let geometry = if slope > 0.0 {
            ((tx * tx + tz * tz) / slope).sqrt() as f32
        } else {
            1.0
        };
        // plane 0 is (h, Dx); plane 1 is (Dz, dh/dx) = h~ (m_dz + i m_dhdx) with
        // m_dz = i lambda uz and m_dhdx = i kx: its real part is dh/dx's, its imaginary Dz's
        m[0] *= geometry;
        m[1].re *= read;
        m[1].im *= geometry;
        m[2] *= read;
        m[3] *= read;
    }
}

/// Out-of-place transpose of an n x n matrix in row blocks, so reads stay in short runs (the
/// tests' reference transform).
#[cfg(test)]
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
