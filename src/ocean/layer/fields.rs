//! The eight fields of a layer at one time: h~(k, t) of eq. 2 times each field's spectral
//! multiplier, two real fields per complex 2-D inverse FFT.

use std::f64::consts::TAU;

use rayon::prelude::*;
use rustfft::num_complex::Complex;

use super::{C32, Layer, signed_index};

impl Layer {
    /// h~(k, t) of eq. 2 for cell `i` (kx-major) in f64.
    #[inline]
    pub(super) fn h_tilde(&self, ix: usize, iz: usize, t: f64) -> Complex<f64> {
        let n = self.n;
        let i = ix * n + iz;
        let a = self.h0[i];
        let b = self.h0[((n - ix) & (n - 1)) * n + ((n - iz) & (n - 1))];
        if a == C32::default() && b == C32::default() {
            return Complex::default();
        }
        let dk = TAU / self.size_m;
        let k = (signed_index(ix, n) * dk).hypot(signed_index(iz, n) * dk);
        let omega = crate::ocean::spectrum::dispersion(k, self.depth_m);
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
