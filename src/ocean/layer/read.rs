//! Reads of a layer between its grid points: bilinear (the paper's), in lanes for the
//! renderer's batches, Catmull-Rom bicubic, variance-preserving, and the direct Fourier sum that
//! is the oracle for them.

use std::f64::consts::TAU;

use rayon::prelude::*;
use rustfft::num_complex::Complex;

use super::{FIELD_COUNT, Layer, Texel, field, signed_index};
use crate::ocean::Interp;

/// 25 000 km for the finest default layer) takes the scalar [`split`].
pub(super) const LANE_RANGE: f64 = (1u32 << 30) as f64;

/// [`split`] for lanes of grid coordinates within `LANE_RANGE`, in vector code. Adding
/// 1.5 x 2^52 rounds a coordinate to the nearest integer, whose two's complement is then the
/// low 32 bits of the sum (exact below 2^51); one less where that rounded up is the floor.
/// (A float-to-int cast would be scalar code: Rust's `as` saturates.)
#[inline]
pub(super) fn split_lanes<const LANES: usize>(p: &[f64; LANES]) -> ([i32; LANES], [f32; LANES]) {
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
pub(super) fn split(p: f64) -> (i64, f32) {
    let i = crate::fp::floor_i64(p);
    (i, (p - i as f64) as f32)
}

/// Each field's correlation with itself one texel away: along x, along z, and along the two
/// diagonals (+x +z and +x -z), in [`field`](super::field) order.
pub type LagCorrelations = [[f32; 4]; FIELD_COUNT];

/// Divides each field of a bilinear blend at fractions (fx, fz) by the blend's standard
/// deviation relative to one texel's (see [`Layer::variance_preserving`]).
#[inline]
fn preserve_variance(r: &mut Texel, fx: f32, fz: f32, rho: &LagCorrelations) {
    let (gx, gz) = (1.0 - fx, 1.0 - fz);
    let (a, b) = (gx * gx + fx * fx, gz * gz + fz * fz);
    let (p, q) = (2.0 * gx * fx, 2.0 * gz * fz);
    for (v, rho) in r.iter_mut().zip(rho) {
        let var = a * b + p * b * rho[0] + q * a * rho[1] + 0.5 * p * q * (rho[2] + rho[3]);
        *v /= var.max(1e-6).sqrt();
    }
}

#[inline]
pub(super) fn catmull_rom(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// The mean power a read with `interp` keeps of a wave that advances `theta` radians a texel
/// along one axis, over the positions between grid points: a cosine of random phase read at the
/// fraction t with weights w_i(t) on the texels at offsets o_i has E[v^2] / E[cos^2] =
/// sum_ij w_i w_j cos((o_i - o_j) theta), here averaged over t by 4-point Gauss-Legendre (exact:
/// the integrand is a polynomial of degree at most 6 in t). Bilinear gives (2 + cos theta) / 3.
/// A 2-D read keeps the product of its two axes' (and over a period the cross terms between
/// waves average to zero, so a field read keeps the sum over its waves). A variance-preserving
/// read rescales each field to its grid variance: 1 here, exact for the field's total, not
/// wave by wave (it shifts power towards the shorter waves). A prefiltered read keeps each
/// wave's power of the derivative fields, the only ones this is used for: 1
/// ([`Layer::set_prefilter`]; its heights keep more than 1, by design of their own gain).
pub fn read_power_transfer(interp: Interp, theta: f64) -> f64 {
    const GAUSS: [(f64, f64); 4] = [
        (0.069_431_844_202_973_7, 0.173_927_422_568_726_9),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
    ];
    let mean = |weights: &dyn Fn(f64) -> [f64; 4], taps: usize| -> f64 {
        GAUSS
            .iter()
            .map(|&(t, g)| {
                let w = weights(t);
                let mut sum = 0.0;
                for i in 0..taps {
                    for j in 0..taps {
                        sum += w[i] * w[j] * ((i as f64 - j as f64) * theta).cos();
                    }
                }
                g * sum
            })
            .sum()
    };
    match interp {
        Interp::Bilinear => mean(&|t| [1.0 - t, t, 0.0, 0.0], 2),
        Interp::Bicubic => mean(&|t| catmull_rom(t as f32).map(f64::from), 4),
        Interp::VariancePreserving | Interp::Prefiltered => 1.0,
    }
}

/// The mean product, over the positions between grid points, of a read of a wave on one grid
/// and its read on a grid twice as coarse whose points are every other one of the first's,
/// along one axis: E[b(theta, x) conj b(2 theta, x)], b the read's response to a wave of unit
/// amplitude that advances `theta` radians a texel of the finer grid, relative to the wave
/// itself. With the read's own power ([`read_power_transfer`]) of each, it gives the
/// covariance of a blend of two levels of a layer ([`crate::ocean::levels`]): a 2-D read's is
/// the real part of the product of its two axes'. Each half of the coarse cell is one
/// polynomial in the position, of degree at most 7 for Catmull-Rom, which 4-point
/// Gauss-Legendre integrates exactly. Prefiltered reads divide each grid's by the square root
/// of its bilinear power; so, in place of their own (they rescale each field as a whole),
/// do variance-preserving ones.
pub fn read_cross_transfer(interp: Interp, theta: f64) -> Complex<f64> {
    const GAUSS: [(f64, f64); 4] = [
        (0.069_431_844_202_973_7, 0.173_927_422_568_726_9),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
    ];
    // The response at fraction f of a cell of a grid whose texels the wave advances by `phase`.
    let response = |phase: f64, f: f64| -> Complex<f64> {
        let (w, first): ([f64; 4], f64) = match interp {
            Interp::Bicubic => (catmull_rom(f as f32).map(f64::from), -1.0),
            _ => ([1.0 - f, f, 0.0, 0.0], 0.0),
        };
        w.iter()
            .enumerate()
            .map(|(i, &w)| Complex::from_polar(w, phase * (first + i as f64 - f)))
            .sum()
    };
    let mut c = Complex::new(0.0, 0.0);
    for half in 0..2 {
        for &(t, g) in &GAUSS {
            // the coarse cell's fraction u, the fine cell's 2u - half
            let u = 0.5 * (half as f64 + t);
            c += 0.5 * g * response(theta, 2.0 * u - half as f64) * response(2.0 * theta, u).conj();
        }
    }
    match interp {
        Interp::Prefiltered | Interp::VariancePreserving => {
            let t = |phase: f64| read_power_transfer(Interp::Bilinear, phase);
            c / (t(theta) * t(2.0 * theta)).sqrt()
        }
        Interp::Bilinear | Interp::Bicubic => c,
    }
}

impl Layer {
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

    /// The gradient (dh/dx, dh/dz) of the bilinear blend of h itself at grid coordinates
    /// (px, pz) (wraps): along x the difference across the cell, blended along z, and the other
    /// way round. The slope of the surface the exact intersector meets (over the undisplaced
    /// plane), which keeps sinc^2(theta / 2) of a wave's slope power along its axis where a
    /// bilinear read of the slope fields keeps (2 + cos theta) / 3.
    #[inline]
    pub fn surface_gradient(&self, px: f64, pz: f64) -> [f64; 2] {
        let (ix, fx) = split(px);
        let (iz, fz) = split(pz);
        let h = |dx: i64, dz: i64| self.texel(ix + dx, iz + dz)[field::H] as f64;
        let (fx, fz) = (fx as f64, fz as f64);
        let ddx = (h(1, 0) - h(0, 0)) * (1.0 - fz) + (h(1, 1) - h(0, 1)) * fz;
        let ddz = (h(0, 1) - h(0, 0)) * (1.0 - fx) + (h(1, 1) - h(1, 0)) * fx;
        [ddx * self.inv_dx, ddz * self.inv_dx]
    }

    /// Adds the bilinear reads at the grid coordinates `(px[l], pz[l])` of the first `count`
    /// lanes into `sum[l]`, bit for bit `sum[l] += self.bilinear(px[l], pz[l])`, or with
    /// `preserve` bit for bit `sum[l] += self.variance_preserving(px[l], pz[l])`. The lanes'
    /// cells and weights are computed together (vector code, where `bilinear` spends most of
    /// its instructions one point at a time); each lane then reads its four texels. Lanes past
    /// `count` are computed and not read, whatever they hold.
    #[inline]
    pub fn add_bilinear_lanes<const LANES: usize>(
        &self,
        px: &[f64; LANES],
        pz: &[f64; LANES],
        count: usize,
        preserve: bool,
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
                let t = if preserve {
                    self.variance_preserving(px[l], pz[l])
                } else {
                    self.bilinear(px[l], pz[l])
                };
                add_texel(&mut sum[l], &t);
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
        let rho = preserve.then(|| self.lag_correlations());
        for (l, s) in sum.iter_mut().enumerate().take(count) {
            let mut t = blend(
                std::array::from_fn(|c| &f[cells[c][l] as usize & mask]),
                std::array::from_fn(|c| weights[c][l]),
            );
            if let Some(rho) = rho {
                preserve_variance(&mut t, fx[l], fz[l], rho);
            }
            add_texel(s, &t);
        }
    }

    /// Each field's correlations between neighbouring texels over the whole (periodic) grid:
    /// the realization's own, so a variance-preserving read keeps the grid's variance. A field
    /// that is zero everywhere gets correlations of 1 (its reads stay zero).
    pub fn lag_correlations(&self) -> &LagCorrelations {
        self.lag_correlations.get_or_init(|| {
            let n = self.n;
            let f = &self.fields;
            // per field: the sums of v^2 and of v times its four neighbours
            let sums = (0..n)
                .into_par_iter()
                .map(|iz| {
                    let (row, up) = (&f[iz * n..][..n], &f[(iz + 1) % n * n..][..n]);
                    let mut s = [[0f64; 5]; FIELD_COUNT];
                    for ix in 0..n {
                        let (right, left) = ((ix + 1) % n, (ix + n - 1) % n);
                        let near = [&row[right], &up[ix], &up[right], &up[left]];
                        for (j, s) in s.iter_mut().enumerate() {
                            let v = row[ix][j] as f64;
                            s[0] += v * v;
                            for (s, t) in s[1..].iter_mut().zip(near) {
                                *s += v * t[j] as f64;
                            }
                        }
                    }
                    s
                })
                .reduce(
                    || [[0f64; 5]; FIELD_COUNT],
                    |mut a, b| {
                        for (a, b) in a.iter_mut().zip(&b) {
                            for (a, b) in a.iter_mut().zip(b) {
                                *a += b;
                            }
                        }
                        a
                    },
                );
            sums.map(|s| {
                if s[0] > 0.0 {
                    std::array::from_fn(|l| (s[l + 1] / s[0]) as f32)
                } else {
                    [1.0; 4]
                }
            })
        })
    }

    /// Variance-preserving read at grid coordinates (px, pz) (wraps): the bilinear blend of
    /// each field divided by its standard deviation relative to one texel's. With weights
    /// w = a_i b_j (a = (1 - fx, fx), b = (1 - fz, fz)) and the field's correlations rho one
    /// texel away, the blend's variance over a texel's is sum w_c w_d rho(c - d) =
    /// |a|^2 |b|^2 + 2 a0 a1 |b|^2 rho_x + 2 b0 b1 |a|^2 rho_z + 2 a0 a1 b0 b1 (rho_d1 + rho_d2)
    /// (variance-preserving blending as in Heitz & Neyret 2018, with the texels' correlation).
    /// At a grid point it is the texel; between, each field keeps its grid variance.
    #[inline]
    pub fn variance_preserving(&self, px: f64, pz: f64) -> Texel {
        let mut r = self.bilinear(px, pz);
        let ((_, fx), (_, fz)) = (split(px), split(pz));
        preserve_variance(&mut r, fx, fz, self.lag_correlations());
        r
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
            Interp::Bilinear | Interp::Prefiltered => self.bilinear(px, pz),
            Interp::Bicubic => self.bicubic(px, pz),
            Interp::VariancePreserving => self.variance_preserving(px, pz),
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
