//! Sea water as a smooth dielectric interface over an absorbing body (paper section 5: "each
//! intersection generated a Fresnel reflection and refraction"). Fresnel reflectance is the
//! exact unpolarised one for a dielectric (Born & Wolf); absorption follows Beer-Lambert per RGB
//! channel; light that travels down and never returns to the surface is replaced by the
//! upwelling radiance a remote-sensing reflectance R_rs gives ([`Water::upwelling`]), so the sea
//! has a body colour rather than black.

use glam::Vec3;

pub use crate::config::Water;

/// Unpolarised Fresnel reflectance for light arriving at cosine `cos_i` (> 0) from a medium
/// of index `eta_i` onto one of index `eta_t`. Returns 1 for total internal reflection.
pub fn fresnel(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = eta_i / eta_t;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Mirror reflection of direction `d` about normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of `d` through a surface with normal `n` facing the incoming side (d·n < 0),
/// relative index `eta = eta_i / eta_t`; `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

impl Water {
    /// The radiance a downward ray in the water returns when it never meets the surface again:
    /// the upwelling radiance just below the surface, L_u, under a sky of downwelling
    /// irradiance `irradiance`. It is set so that the water-leaving radiance seen straight down
    /// is R_rs E_d: the path that carries L_u up through the surface weights it by the Fresnel
    /// transmittance 1 - F, so L_u = R_rs E_d / (1 - F(0)), and other view angles get the
    /// transmittance they should. (The n^2 radiance scaling cancels on paths that cross air ->
    /// water -> air.)
    pub fn upwelling(&self, irradiance: Vec3) -> Vec3 {
        let t0 = 1.0 - fresnel(1.0, 1.0, self.ior);
        Vec3::from(self.upwelling_rrs) * irradiance / t0
    }

    /// Beer-Lambert transmittance over `distance` metres of water.
    pub fn transmittance(&self, distance: f32) -> Vec3 {
        Vec3::from(self.absorption.map(|a| (-a * distance.max(0.0)).exp()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_known_values() {
        // normal incidence: ((n-1)/(n+1))^2 = 0.02037 for n = 1.333
        assert!((fresnel(1.0, 1.0, 1.333) - 0.020_37).abs() < 1e-4);
        // grazing incidence reflects everything
        assert!(fresnel(0.0, 1.0, 1.333) > 0.999);
        // Brewster angle (53.1 deg): p-polarised reflectance vanishes; rs = -0.280, F = rs^2 / 2
        let brewster = 1.333f32.atan();
        let f = fresnel(brewster.cos(), 1.0, 1.333);
        assert!((f - 0.0392).abs() < 1e-4, "{f}");
        // total internal reflection from below past the critical angle (48.6 degrees)
        assert_eq!(fresnel(50f32.to_radians().cos(), 1.333, 1.0), 1.0);
        // below it, reflectance rises towards 1 as the critical angle nears (0.0556 at 40 deg)
        assert!((fresnel(40f32.to_radians().cos(), 1.333, 1.0) - 0.0556).abs() < 2e-4);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3::Y;
        let theta = 50f32.to_radians();
        let d = Vec3::new(theta.sin(), -theta.cos(), 0.0);
        let t = refract(d, n, 1.0 / 1.333).unwrap();
        assert!((t.x - theta.sin() / 1.333).abs() < 1e-6 && t.y < 0.0);
        // from below at 60 degrees: total internal reflection
        let up = Vec3::new(60f32.to_radians().sin(), 60f32.to_radians().cos(), 0.0);
        assert!(refract(up, -Vec3::Y, 1.333).is_none());
    }

    #[test]
    fn water_leaving_radiance_at_nadir_is_rrs_times_irradiance() {
        let w = Water::default();
        let e = Vec3::new(2.0, 3.0, 5.0);
        // Straight down, the upwelling radiance crosses the surface with weight 1 - F(0).
        let leaving = w.upwelling(e) * (1.0 - fresnel(1.0, w.ior, 1.0));
        let want = Vec3::from(w.upwelling_rrs) * e;
        assert!((leaving - want).abs().max_element() < 1e-6 * want.max_element());
    }

    #[test]
    fn default_absorption_is_pope_and_fry_at_600_550_450_nm() {
        // Pope & Fry 1997, pure water: 0.2224 (600 nm), 0.0565 (550 nm), 0.00922 (450 nm) 1/m.
        let a = Water::default().absorption;
        for (got, want) in a.iter().zip([0.2224, 0.0565, 0.00922]) {
            assert!((got / want - 1.0).abs() < 0.01, "{a:?}");
        }
    }

    proptest::proptest! {
        /// Reflectance is a fraction; the same interface seen from the other side along the
        /// refracted direction reflects the same fraction (reciprocity of the unpolarised
        /// Fresnel equations); and `fresnel` reports total internal reflection exactly when
        /// `refract` finds no refracted direction.
        #[test]
        fn fresnel_is_bounded_reciprocal_and_agrees_with_refract(
            cos_i in 0.0f32..=1.0,
            ior in 1.0f32..2.5,
            from_dense in proptest::bool::ANY,
        ) {
            let (eta_i, eta_t) = if from_dense { (ior, 1.0) } else { (1.0, ior) };
            let f = fresnel(cos_i, eta_i, eta_t);
            proptest::prop_assert!((0.0..=1.0).contains(&f), "F = {f}");
            let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
            let d = Vec3::new(sin_i, -cos_i, 0.0);
            let t = refract(d, Vec3::Y, eta_i / eta_t);
            // (F also reaches 1 at exactly grazing incidence, where light still refracts.)
            proptest::prop_assert_eq!(f == 1.0, t.is_none() || cos_i == 0.0, "cos_i {} F {}", cos_i, f);
            // Reciprocity; near grazing, f32 keeps too few digits of cos for a tight check.
            if let Some(t) = t.filter(|_| cos_i > 0.05) {
                let cos_t = -t.y;
                let back = fresnel(cos_t, eta_t, eta_i);
                proptest::prop_assert!((back - f).abs() < 2e-4, "F {f} vs reverse {back}");
            }
        }
    }
}
