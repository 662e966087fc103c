//! The waves below a ray's footprint as a microfacet surface: an anisotropic Gaussian slope
//! distribution (Beckmann) around the resolved normal, with the covariance of the unresolved
//! waves ([`crate::ocean::slopes`]), Smith's uncorrelated masking, and visible-normal sampling
//! (Heitz & d'Eon 2014, in pbrt-v3's form with Jakob's numerical inversion). Walter, Marschner,
//! Li & Torrance (2007) give the reflection and refraction through such a surface.
//!
//! Everything here works in a local frame: z along the resolved (macro) normal on the air side,
//! x and y along the principal axes of the slope covariance, where a Beckmann distribution of
//! roughness alpha_i = sqrt(2) sigma_i has slopes of variance sigma_i^2. Directions on the water
//! side are mirrored into the upper half first ([`Lobe::local`]): a zero-mean Gaussian of
//! slopes is the same seen from either side.

use glam::Vec3;

const SQRT_PI_INV: f32 = 0.564_189_6;

/// Smallest roughness along an axis: a covariance with a zero eigenvalue (long-crested waves)
/// keeps a finite density.
const MIN_ALPHA: f32 = 1e-4;

/// An anisotropic Gaussian slope distribution around a macro normal.
#[derive(Clone, Copy, Debug)]
pub struct Lobe {
    /// The local frame: x, y along the principal axes of the slopes, z the macro normal.
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
    /// Beckmann roughness along x and y.
    pub alpha: [f32; 2],
    /// The slopes of the distribution's centre along x and y: zero for a lobe around its own
    /// z ([`Self::new`]), the resolved normal's slopes for one around the vertical
    /// ([`Self::around`]). Only the by-area density and sampling read it.
    pub mean: [f32; 2],
}

impl Lobe {
    /// The lobe of slopes of covariance `cov` = (xx, xz, zz) in the world's x and z around the
    /// unit macro normal `n` (air side up), or `None` when the slopes are too small to matter
    /// (a trace below 1e-10: a delta interface).
    pub fn new(n: Vec3, cov: [f32; 3]) -> Option<Lobe> {
        let [a, b, c] = cov;
        if (a + c).is_nan() || a + c <= 1e-10 {
            return None;
        }
        // The tangent plane's axes nearest the world's x and z: a slope along them is the
        // world slope (the covariance is given for the flat sea; n is within a few degrees of
        // the vertical wherever a lobe is wide).
        let t1 = (Vec3::X - Vec3::X.dot(n) * n).normalize_or(Vec3::X);
        // n and t1 are unit and orthogonal, so their cross product is unit (up to rounding)
        // unless t1 fell back to x along n
        let t2 = n.cross(t1);
        let t2 = if t2.length_squared() > 0.5 {
            t2
        } else {
            Vec3::Z
        };
        // n x t1 is -z for n = +y (slopes along t2 are minus the z slopes) and +z for n = -y
        // (the water side, where both slopes change sign): the cross term follows t1.x t2.z.
        let b = b * (t1.x * t2.z);
        let half = 0.5 * (a - c);
        let root = (half * half + b * b).sqrt();
        let (l1, l2) = (0.5 * (a + c) + root, (0.5 * (a + c) - root).max(0.0));
        // The eigenvector of l1: (root + half, b) or, where that vanishes (b = 0, c > a),
        // (b, root - half); their cosine and sine in the (t1, t2) plane.
        let (ex, ey) = if half >= 0.0 {
            (root + half, b)
        } else {
            (b, root - half)
        };
        let norm = (ex * ex + ey * ey).sqrt();
        let (co, s) = if norm > 0.0 {
            (ex / norm, ey / norm)
        } else {
            (1.0, 0.0)
        };
        Some(Lobe {
            x: co * t1 + s * t2,
            y: -s * t1 + co * t2,
            z: n,
            alpha: [
                (2.0 * l1).sqrt().max(MIN_ALPHA),
                (2.0 * l2).sqrt().max(MIN_ALPHA),
            ],
            mean: [0.0; 2],
        })
    }

    /// The lobe of slopes of covariance `cov` added to the slopes of the unit normal `n`, both
    /// measured from the vertical `up` (air side up, or both mirrored to the water side): the
    /// sum of the resolved and the unresolved waves' slopes, as the normal of a point of the
    /// pixel has them. A lobe around `n` itself ([`Self::new`]) rotates the unresolved slopes
    /// with the resolved normal instead, which tilts and narrows them by the resolved slope's
    /// square. `None` as for [`Self::new`], or where `n` lies in the horizontal plane.
    pub fn around(up: Vec3, n: Vec3, cov: [f32; 3]) -> Option<Lobe> {
        let mut lobe = Lobe::new(up, cov)?;
        let nz = n.dot(lobe.z);
        if nz <= 0.0 {
            return None;
        }
        lobe.mean = [-n.dot(lobe.x) / nz, -n.dot(lobe.y) / nz];
        Some(lobe)
    }

    /// `w` in the local frame, and whether it was on the water side (then mirrored to z > 0).
    #[inline]
    pub fn local(&self, w: Vec3) -> (Vec3, bool) {
        let l = Vec3::new(w.dot(self.x), w.dot(self.y), w.dot(self.z));
        if l.z < 0.0 {
            (Vec3::new(l.x, l.y, -l.z), true)
        } else {
            (l, false)
        }
    }

    /// A local direction back in the world, mirrored back to the water side if `below`.
    #[inline]
    pub fn world(&self, l: Vec3, below: bool) -> Vec3 {
        let z = if below { -l.z } else { l.z };
        l.x * self.x + l.y * self.y + z * self.z
    }

    /// The microfacet normal density D(m) (local, m.z > 0), per steradian of m projected
    /// onto the macro plane: it integrates to 1 against m.z.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let cos2 = m.z * m.z;
        let (sx, sy) = (
            (-m.x / m.z - self.mean[0]) / self.alpha[0],
            (-m.y / m.z - self.mean[1]) / self.alpha[1],
        );
        (-(sx * sx + sy * sy)).exp()
            / (std::f32::consts::PI * self.alpha[0] * self.alpha[1] * cos2 * cos2)
    }

    /// The smallest exponent e of the lobe's density (e^-e of its peak) with which its normals
    /// may reflect world direction `wo` into some direction within `reach` radians of world
    /// direction `w`: the half vector's slopes, less the reach as it moves them, measured in
    /// roughnesses from the lobe's centre, squared (0 where the half vector is undefined or
    /// below the lobe). Moving w by an angle moves the half vector by up to that over |wo + w|
    /// (half of it at normal incidence, more at grazing), and its slope by that over cos^2 of
    /// its tilt; the reach is taken at twice that. A question of effort, not of the estimate:
    /// how many samples to spend there.
    pub fn reach_exponent(&self, wo: Vec3, w: Vec3, reach: f32) -> f32 {
        let sum = wo + w;
        let len = sum.length();
        if len <= 1e-3 {
            return 0.0;
        }
        let (h, below) = self.local(sum / len);
        if below || h.z <= 1e-3 {
            return 0.0;
        }
        let r = 2.0 * reach / (len * h.z * h.z);
        let sx = ((-h.x / h.z - self.mean[0]).abs() - r).max(0.0) / self.alpha[0];
        let sy = ((-h.y / h.z - self.mean[1]).abs() - r).max(0.0) / self.alpha[1];
        sx * sx + sy * sy
    }

    /// Smith's Lambda for local direction `w` (either side: |w.z| is used).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos = w.z.abs();
        let sin2 = (w.x * w.x + w.y * w.y).max(0.0);
        if sin2 == 0.0 {
            return 0.0;
        }
        // alpha along w's azimuth: sqrt(cos^2 phi ax^2 + sin^2 phi ay^2), times tan theta
        let ax = w.x * self.alpha[0];
        let ay = w.y * self.alpha[1];
        let alpha_tan = (ax * ax + ay * ay).sqrt() / cos;
        let a = 1.0 / alpha_tan;
        if a > 5.0 {
            return 0.0;
        }
        (0.5 * (erf(a) - 1.0) + (-a * a).exp() * SQRT_PI_INV / (2.0 * a)).max(0.0)
    }

    /// Smith's masking of local direction `w`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// A microfacet normal m (local, z > 0) drawn by area: its slopes Gaussian with the lobe's
    /// covariance (Box-Muller), as the normal at a uniformly drawn point of the surface. Its
    /// density per steradian of m is D(m) m.z.
    pub fn sample_area(&self, u1: f32, u2: f32) -> Vec3 {
        let r = (-2.0 * (1.0 - u1).max(1e-30).ln()).sqrt();
        let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
        let k = std::f32::consts::FRAC_1_SQRT_2;
        let (sx, sy) = (
            k * self.alpha[0] * r * c + self.mean[0],
            k * self.alpha[1] * r * s + self.mean[1],
        );
        Vec3::new(-sx, -sy, 1.0).normalize()
    }

    /// A microfacet normal m (local, z > 0) visible from local `wo` (z > 0), distributed as
    /// [`Self::pdf_visible`], from two uniform numbers.
    pub fn sample_visible(&self, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
        let [ax, ay] = self.alpha;
        // Stretch to the unit-roughness configuration, sample its slopes, rotate, unstretch.
        let s = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize();
        let (sx, sy) = sample_slopes_11(s.z, u1, u2);
        let sin = (s.x * s.x + s.y * s.y).sqrt();
        let (cos_phi, sin_phi) = if sin > 0.0 {
            (s.x / sin, s.y / sin)
        } else {
            (1.0, 0.0)
        };
        let (rx, ry) = (cos_phi * sx - sin_phi * sy, sin_phi * sx + cos_phi * sy);
        Vec3::new(-ax * rx, -ay * ry, 1.0).normalize()
    }

    /// The density of [`Self::sample_visible`]: D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z.
    pub fn pdf_visible(&self, wo: Vec3, m: Vec3) -> f32 {
        let c = wo.dot(m);
        if c <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * c * self.d(m) / wo.z
    }

    /// The density, per steradian, of reflecting local `wo` into local `wi` (both z > 0) by a
    /// visible normal sampled with [`Self::sample_visible`].
    pub fn reflection_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = (wo + wi).normalize_or_zero();
        let c = wo.dot(h);
        if c <= 0.0 {
            return 0.0;
        }
        self.pdf_visible(wo, h) / (4.0 * c)
    }

    /// The reflection BSDF times the cosine, f_r(wo, wi) |wi.z|, for a Fresnel reflectance
    /// `fresnel` at the half vector (both local, z > 0): F D(h) G1(wo) G1(wi) / (4 wo.z).
    pub fn reflection_cos(&self, wo: Vec3, wi: Vec3, fresnel: f32) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        fresnel * self.d(h) * self.g1(wo) * self.g1(wi) / (4.0 * wo.z)
    }
}

/// The power heuristic's weight (Veach, beta = 2) for a sample from the technique of density
/// `pdf` against the other's `other`, one sample each.
#[inline]
pub fn power_heuristic(pdf: f32, other: f32) -> f32 {
    let (a, b) = (pdf * pdf, other * other);
    if a == 0.0 { 0.0 } else { a / (a + b) }
}

/// Slopes of the unit-roughness Beckmann distribution of visible normals seen at cosine
/// `cos_theta`: pbrt-v3's `BeckmannSample11` (Heitz & d'Eon 2014, with W. Jakob's numerical
/// inversion of the x marginal).
fn sample_slopes_11(cos_theta: f32, u1: f32, u2: f32) -> (f32, f32) {
    if cos_theta > 0.9999 {
        let r = (-(1.0 - u1).max(1e-12).ln()).sqrt();
        let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
        return (r * c, r * s);
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let tan_theta = sin_theta / cos_theta;
    let cot_theta = 1.0 / tan_theta;
    // Search the interval [a, c] for the inverse of the slope's CDF, by Newton with bisection.
    let (mut a, mut c) = (-1.0f32, erf(cot_theta));
    let x = u1.max(1e-6);
    let theta = cos_theta.acos();
    let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    let mut b = c - (1.0 + c) * (1.0 - x).powf(fit);
    let normalization = 1.0 / (1.0 + c + SQRT_PI_INV * tan_theta * (-cot_theta * cot_theta).exp());
    for _ in 0..9 {
        if !(b >= a && b <= c) {
            b = 0.5 * (a + c);
        }
        let inv = erf_inv(b);
        let value = normalization * (1.0 + b + SQRT_PI_INV * tan_theta * (-inv * inv).exp()) - x;
        let derivative = normalization * (1.0 - inv * tan_theta);
        if value.abs() < 1e-5 {
            break;
        }
        if value > 0.0 {
            c = b;
        } else {
            a = b;
        }
        b -= value / derivative;
    }
    (erf_inv(b), erf_inv(2.0 * u2.max(1e-6) - 1.0))
}

/// erf(x), within 1.5e-7 (Abramowitz & Stegun 7.1.26).
pub fn erf(x: f32) -> f32 {
    let (a1, a2, a3, a4, a5, p) = (
        0.254_829_6f32,
        -0.284_496_72,
        1.421_413_8,
        -1.453_152,
        1.061_405_4,
        0.327_591_1,
    );
    let s = x.signum();
    let x = x.abs();
    let t = 1.0 / (1.0 + p * x);
    let y = 1.0 - (((((a5 * t + a4) * t) + a3) * t + a2) * t + a1) * t * (-x * x).exp();
    s * y
}

/// The inverse of erf on (-1, 1): M. Giles' single-precision approximation (2010), as pbrt-v3.
pub fn erf_inv(x: f32) -> f32 {
    let x = x.clamp(-0.99999, 0.99999);
    let mut w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        w -= 2.5;
        let mut p = 2.810_226_4e-8f32;
        for c in [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            0.000_218_580_87,
            -0.001_253_725,
            -0.004_177_681_6,
            0.246_640_73,
            1.501_409_4,
        ] {
            p = c + p * w;
        }
        p
    } else {
        w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_26f32;
        for c in [
            0.000_100_950_56,
            0.001_349_343_2,
            -0.003_673_428_4,
            0.005_739_507_7,
            -0.007_622_461_3,
            0.009_438_870_5,
            1.001_674,
            2.832_976_8,
        ] {
            p = c + p * w;
        }
        p
    };
    p * x
}

mod facing;

#[cfg(test)]
mod tests;
