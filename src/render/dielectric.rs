//! The rough dielectric objects of `material = "glass"` are made of: GGX microfacets that
//! reflect and refract (Walter, Marschner, Li & Torrance 2007, "Microfacet models for
//! refraction through rough surfaces"; as pbrt-v4's `DielectricBxDF`), the exact Fresnel
//! equations of an unpolarised dielectric, Smith's height-correlated masking-shadowing, and
//! sampling by visible normals ([`Ggx::visible_normal`]) with reflection or refraction chosen by
//! the microfacet's Fresnel.
//!
//! Directions are in a frame whose z is the normal on the side the light arrives from (`wo.z >
//! 0`); `eta` is the index of refraction across the surface over the index on `wo`'s side.
//! Paths carry basic radiance L / n^2, which refraction conserves (radiance itself is
//! compressed by eta^2 into the narrower cone of the denser medium): the sea's interface does
//! the same, and as the camera and every light are in the air (n = 1) the image is the
//! radiance's. So the refracted lobe here has no 1 / eta^2.

use glam::Vec3;

use super::ggx::Ggx;
use super::water::fresnel;

/// The Fresnel reflectance of an unpolarised wave meeting a dielectric interface at cosine
/// `cos_i` (> 0) from the side with relative index `eta` (transmitted side over incident):
/// 1 past total internal reflection (the sea's own [`fresnel`]).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    fresnel(cos_i, 1.0, eta)
}

/// `wo` refracted through a microfacet of normal `m` (wo.m > 0) into a medium of relative
/// index `eta`; `None` past total internal reflection.
fn refract(wo: Vec3, m: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(m);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wo / eta + (cos_i / eta - cos_t) * m)
}

/// A rough dielectric interface: roughness `alpha` and relative index `eta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    pub alpha: f32,
    pub eta: f32,
}

/// One sampled scattering: the new direction, its weight f |cos| / pdf, its density, and
/// whether it was refracted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricSample {
    pub wi: Vec3,
    pub weight: f32,
    pub pdf: f32,
    pub refracted: bool,
}

impl RoughDielectric {
    fn ggx(&self) -> Ggx {
        Ggx {
            alpha: self.alpha,
            f0: Vec3::ZERO,
        }
    }

    /// The BSDF f(wo, wi) and the density [`Self::sample`] gives `wi` (wo.z > 0; `wi` on either
    /// side: reflection above, refraction below).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        let g = self.ggx();
        if wo.z <= 0.0 || wi.z == 0.0 {
            return (0.0, 0.0);
        }
        let reflect = wi.z > 0.0;
        // the generalised half vector, turned to the normal's side
        let m = if reflect { wo + wi } else { wo + wi * self.eta };
        if m.length_squared() == 0.0 {
            return (0.0, 0.0);
        }
        let m = m.normalize() * m.z.signum();
        let (om, im) = (wo.dot(m), wi.dot(m));
        // microfacets seen from behind by either direction carry nothing
        if om <= 0.0 || (reflect && im <= 0.0) || (!reflect && im >= 0.0) {
            return (0.0, 0.0);
        }
        let fr = fresnel_dielectric(om, self.eta);
        let (d, g2) = (g.d(m), g.g2(wo, wi));
        // visible normals' density: G1(wo) wo.m D(m) / wo.z
        let visible = g.g1(wo) * om * d / wo.z;
        if reflect {
            let f = fr * d * g2 / (4.0 * wo.z * wi.z);
            (f, fr * visible / (4.0 * om))
        } else {
            let denom = (im + om / self.eta).powi(2);
            let f = (1.0 - fr) * d * g2 * (im * om / (wo.z * wi.z * denom)).abs();
            (f, (1.0 - fr) * visible * im.abs() / denom)
        }
    }

    /// A direction drawn from the visible normals seen from `wo` (wo.z > 0), reflected with the
    /// microfacet's Fresnel reflectance and refracted otherwise, from three uniform numbers;
    /// `None` when it leaves on the wrong side of the surface (masked: its light is lost).
    pub fn sample(&self, wo: Vec3, u1: f32, u2: f32, u3: f32) -> Option<DielectricSample> {
        let g = self.ggx();
        let m = g.visible_normal(wo, u1, u2);
        let om = wo.dot(m);
        if om <= 0.0 {
            return None;
        }
        let fr = fresnel_dielectric(om, self.eta);
        let visible = g.g1(wo) * om * g.d(m) / wo.z;
        let refracted = u3 >= fr;
        let wi = if refracted {
            refract(wo, m, self.eta)?
        } else {
            2.0 * om * m - wo
        };
        if (wi.z < 0.0) != refracted || wi.z == 0.0 {
            return None;
        }
        let g2_over_g1 = g.g2(wo, wi) / g.g1(wo);
        let (weight, pdf) = if refracted {
            let im = wi.dot(m);
            let denom = (im + om / self.eta).powi(2);
            (g2_over_g1, (1.0 - fr) * visible * im.abs() / denom)
        } else {
            (g2_over_g1, fr * visible / (4.0 * om))
        };
        Some(DielectricSample {
            wi,
            weight,
            pdf,
            refracted,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Normal incidence on glass reflects ((n - 1) / (n + 1))^2 = 4 %; grazing reflects all;
    /// from inside past the critical angle everything is reflected.
    #[test]
    fn fresnel_has_its_known_values() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!(fresnel_dielectric(1e-4, 1.5) > 0.99);
        // critical angle from inside glass: sin = 1 / 1.5
        let critical = (1.0f32 / 1.5).asin();
        assert_eq!(fresnel_dielectric((critical + 0.01).cos(), 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric((critical - 0.05).cos(), 1.0 / 1.5) < 1.0);
    }

    /// The sampler's weights are f |cos| / pdf of its own `eval` (each sample checked), and
    /// their mean is the BSDF's integral over the sphere (uniform sampling of `eval`): energy is
    /// only lost to masking, never made, entering glass and leaving it.
    #[test]
    fn the_samples_weights_are_the_bsdfs_integral() {
        let mut rng = Rng::keyed(&[35, 11]);
        for (alpha, eta) in [(0.05f32, 1.5f32), (0.3, 1.5), (0.3, 1.0 / 1.5), (0.6, 1.33)] {
            let b = RoughDielectric { alpha, eta };
            for theta in [0.2f32, 0.9, 1.3] {
                let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                let n = 200_000;
                let mut sampled = 0.0f64;
                for _ in 0..n {
                    let Some(s) = b.sample(wo, rng.f32(), rng.f32(), rng.f32()) else {
                        continue;
                    };
                    let (f, pdf) = b.eval(wo, s.wi);
                    let direct = f * s.wi.z.abs() / pdf;
                    assert!(
                        (direct / s.weight - 1.0).abs() < 1e-2 && (pdf / s.pdf - 1.0).abs() < 1e-2,
                        "{alpha} {eta} {theta}: {direct} {} {pdf} {}",
                        s.weight,
                        s.pdf
                    );
                    sampled += s.weight as f64;
                }
                sampled /= n as f64;
                assert!(
                    sampled <= 1.0 + 1e-3 && sampled > 0.5,
                    "{alpha} {eta} {theta}: {sampled}"
                );
                if alpha >= 0.3 {
                    let (mut integral, m) = (0.0f64, 800_000);
                    for _ in 0..m {
                        let z = 1.0 - 2.0 * rng.f32();
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        let phi = std::f32::consts::TAU * rng.f32();
                        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                        let f = b.eval(wo, wi).0;
                        integral += (f * z.abs() * 2.0 * std::f32::consts::TAU) as f64;
                    }
                    integral /= m as f64;
                    assert!(
                        (sampled - integral).abs() < 0.03,
                        "{alpha} {eta} {theta}: samples {sampled}, integral {integral}"
                    );
                }
            }
        }
    }
}
