//! The water interface at a hit as the integrator uses it: the interface's normals, the
//! Fresnel weight, and the reflected and refracted directions leaving it (the paper's delta
//! Fresnel split), with the wrong-side policy applied; and which branches a path follows.

use glam::Vec3;

use super::counters::Counters;
use super::integrator::{SceneRef, TraceSettings};
use super::interface::{SurfacePoint, bend_normal, keep_side, surface_point};
use super::water::{fresnel, reflect, refract};
use crate::accel::Hit;
use crate::config::WrongSide;
use crate::rng::Rng;

/// What one hit does to a path: where it is, which way the medium changes, the attenuation of
/// the segment that reached it, and the two directions leaving it with the Fresnel weight.
#[derive(Clone, Copy)]
pub(super) struct Scatter {
    pub(super) sp: SurfacePoint,
    pub(super) from_below: bool,
    pub(super) attenuation: Vec3,
    pub(super) fresnel: f32,
    /// `None`: the wrong-side policy ended this branch.
    pub(super) reflected: Option<Vec3>,
    /// `None` on total internal reflection; `Some(None)` when the policy ended the branch.
    pub(super) refracted: Option<Option<Vec3>>,
}

impl Scatter {
    /// A placeholder for the unused slots of a batch's array.
    pub(super) const NONE: Scatter = Scatter {
        sp: SurfacePoint {
            p: Vec3::ZERO,
            ng: Vec3::Y,
            err: Vec3::ZERO,
            prim: 0,
        },
        from_below: false,
        attenuation: Vec3::ZERO,
        fresnel: 0.0,
        reflected: None,
        refracted: None,
    };
}

impl SceneRef<'_> {
    /// Shading at a hit of a ray travelling along `d`, whose shading normal (air side up) is
    /// `shading` ([`Self::shading_normals`]): the interface's normals, the Fresnel weight and
    /// the reflected and refracted directions.
    pub(super) fn scatter(
        &self,
        d: Vec3,
        hit: &Hit,
        shading: Vec3,
        settings: &TraceSettings,
        c: &mut Counters,
    ) -> Scatter {
        let sp = surface_point(self.accel.mesh(), hit);
        let from_below = d.dot(sp.ng) > 0.0;
        let attenuation = if from_below {
            settings.water.transmittance(hit.t)
        } else {
            Vec3::ONE
        };

        // Shading normal facing the incoming ray, and the geometric one likewise.
        let mut ns = shading;
        let (ng, eta_i, eta_t) = if from_below {
            (-sp.ng, settings.water.ior, 1.0)
        } else {
            (sp.ng, 1.0, settings.water.ior)
        };
        if from_below {
            ns = -ns;
        }
        let policy = settings.wrong_side;
        let mut dead = false;
        if d.dot(ns) >= 0.0 {
            c.backfacing_shading += 1;
            match policy {
                WrongSide::Mirror => ns = ng,
                WrongSide::Flip => ns = -ns,
                // Bent below, as every other normal is.
                WrongSide::Bend => {}
                WrongSide::Terminate => dead = true,
            }
        }
        if policy == WrongSide::Bend {
            let bent = bend_normal(ng, -d, ns);
            c.bent += u64::from(bent != ns);
            ns = bent;
        }
        let cos_i = -d.dot(ns);
        let fresnel = fresnel(cos_i, eta_i, eta_t);
        let (reflected, refracted) = if dead {
            c.terminated += 1;
            (None, Some(None))
        } else {
            (
                keep_side(reflect(d, ns), ng, true, policy, c),
                refract(d, ns, eta_i / eta_t).map(|t| keep_side(t, ng, false, policy, c)),
            )
        };
        Scatter {
            sp,
            from_below,
            attenuation,
            fresnel,
            reflected,
            refracted,
        }
    }
}

/// A branch leaving a hit: its direction and whether it travels in the water (`None`: not
/// followed, radiance zero).
pub(super) type Branch = Option<(Vec3, bool)>;

/// The branches a hit at `segment` follows, first then second, and whether both are (then F
/// and 1 - F weigh them; otherwise the first carries the whole radiance): the reflection alone
/// on total internal reflection; both, up to `branch_depth`; past it one, chosen with
/// probability F (drawn from `rng`: the estimator stays unbiased). The reflected ray stays in
/// the medium it came from, the refracted one changes it.
pub(super) fn branches(
    s: &Scatter,
    segment: u32,
    settings: &TraceSettings,
    rng: &mut Rng,
) -> (Branch, Branch, bool) {
    let reflected = s.reflected.map(|w| (w, s.from_below));
    let refracted = |t: Option<Vec3>| t.map(|w| (w, !s.from_below));
    match s.refracted {
        None => (reflected, None, false),
        Some(t) if segment < settings.branch_depth => (reflected, refracted(t), true),
        Some(t) => {
            if rng.f32() < s.fresnel {
                (reflected, None, false)
            } else {
                (refracted(t), None, false)
            }
        }
    }
}
