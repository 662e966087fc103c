//! The GGX (Trowbridge-Reitz) microfacet reflection objects of `material = "metal"` use: an
//! isotropic distribution of roughness alpha, Smith's height-correlated masking-shadowing,
//! Schlick's Fresnel from the reflectance at normal incidence, and sampling by visible normals
//! (Heitz 2018, "Sampling the GGX distribution of visible normals"). Directions are in a frame
//! whose z is the surface normal; `wo` looks back along the incoming ray.

use glam::Vec3;

/// A GGX conductor of roughness `alpha` (0.001 to 1) and normal-incidence reflectance `f0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
    pub f0: Vec3,
}

impl Ggx {
    /// D(m): the density of microfacet normals per unit projected area.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let k = c2 * (a2 - 1.0) + 1.0;
        a2 / (std::f32::consts::PI * k * k)
    }

    /// Smith's Lambda for direction `w`.
    fn lambda(&self, w: Vec3) -> f32 {
        let c2 = (w.z * w.z).max(1e-12);
        let t2 = ((1.0 - c2) / c2).max(0.0);
        0.5 * ((1.0 + self.alpha * self.alpha * t2).sqrt() - 1.0)
    }

    /// G1(w): the share of the visible microfacets not masked along `w`.
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// G2(wo, wi), height-correlated.
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Schlick's Fresnel at cosine `c` between the direction and the microfacet normal.
    pub fn fresnel(&self, c: f32) -> Vec3 {
        let k = (1.0 - c.clamp(0.0, 1.0)).powi(5);
        self.f0 + (Vec3::ONE - self.f0) * k
    }

    /// The BSDF f(wo, wi) (both above the surface; zero otherwise).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize();
        self.fresnel(wi.dot(h)) * (self.d(h) * self.g2(wo, wi) / (4.0 * wo.z * wi.z))
    }

    /// The density of [`Self::sample`] at `wi`, per steradian.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        // D_wo(h) / (4 wo.h), D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z
        self.g1(wo) * self.d(h) / (4.0 * wo.z)
    }

    /// A microfacet normal drawn from those visible from `wo` (above the surface), from two
    /// uniform numbers: density G1(wo) max(0, wo.m) D(m) / wo.z.
    pub fn visible_normal(&self, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
        let a = self.alpha;
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        let r = u1.sqrt();
        let phi = std::f32::consts::TAU * u2;
        let (p1, mut p2) = (r * phi.cos(), r * phi.sin());
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-7)).normalize()
    }

    /// A reflected direction drawn from the visible normals seen from `wo`, from two uniform
    /// numbers, and its weight f cos / pdf = F G2 / G1(wo); `None` when it leaves below the
    /// surface (the path ends: its light is the masking's loss).
    pub fn sample(&self, wo: Vec3, u1: f32, u2: f32) -> Option<(Vec3, Vec3)> {
        let m = self.visible_normal(wo, u1, u2);
        let wi = 2.0 * wo.dot(m) * m - wo;
        if wi.z <= 0.0 {
            return None;
        }
        Some((
            wi,
            self.fresnel(wi.dot(m)) * (self.g2(wo, wi) / self.g1(wo)),
        ))
    }
}

/// An orthonormal frame whose z is a unit normal: directions into it and back.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    pub fn new(n: Vec3) -> Frame {
        let (t, b) = n.any_orthonormal_pair();
        Frame { t, b, n }
    }

    pub fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }

    pub fn from_local(&self, w: Vec3) -> Vec3 {
        w.x * self.t + w.y * self.b + w.z * self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// What the sampler's weights average to is what the BSDF integrates to: the directional
    /// albedo of a white conductor, E[F G2 / G1] over its samples against the integral of
    /// f cos over the hemisphere by uniform sampling, at three roughnesses and three angles;
    /// and the pdf is the sampler's (f cos / pdf equals the weight it returns).
    #[test]
    fn the_samples_weights_are_the_bsdfs_integral() {
        let mut rng = Rng::keyed(&[35, 9]);
        for alpha in [0.05f32, 0.3, 0.8] {
            let g = Ggx {
                alpha,
                f0: Vec3::splat(0.9),
            };
            for theta in [0.0f32, 0.8, 1.3] {
                let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                let n = 200_000;
                let mut sampled = 0.0f64;
                for _ in 0..n {
                    if let Some((wi, w)) = g.sample(wo, rng.f32(), rng.f32()) {
                        sampled += w.x as f64;
                        let direct = g.f(wo, wi).x * wi.z / g.pdf(wo, wi);
                        assert!(
                            (direct / w.x - 1.0).abs() < 2e-3,
                            "{alpha} {theta}: {direct} {w}"
                        );
                    }
                }
                sampled /= n as f64;
                // uniform over the hemisphere: pdf 1 / (2 pi); cosine-weighted for smooth ones
                let mut integral = 0.0f64;
                let m = 400_000;
                for _ in 0..m {
                    let (u1, u2) = (rng.f32(), rng.f32());
                    let r = u1.sqrt();
                    let phi = std::f32::consts::TAU * u2;
                    let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt());
                    // cosine-weighted: f cos / (cos / pi) = pi f
                    integral += (std::f32::consts::PI * g.f(wo, wi).x) as f64;
                }
                integral /= m as f64;
                if alpha >= 0.3 {
                    assert!(
                        (sampled - integral).abs() < 0.01,
                        "alpha {alpha}, theta {theta}: samples {sampled}, integral {integral}"
                    );
                }
                // energy only lost (to masking), never made
                assert!(
                    sampled <= 1.0 && sampled > 0.1,
                    "{alpha} {theta}: {sampled}"
                );
            }
        }
    }
}
