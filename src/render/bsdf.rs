//! The water interface at a hit as the integrator uses it: the interface's normals, the
//! Fresnel weight, and the reflected and refracted directions leaving it, with the wrong-side
//! policy applied; and which branches a path follows.
//!
//! A smooth hit (vertex and mapped normals, or a filtered hit whose footprint resolves every
//! wave) is the paper's delta Fresnel split about the shading normal. A rough hit (filtered
//! normals, waves below the footprint) first draws a microfacet normal m from the visible
//! normals of the unresolved slopes around the resolved normal ([`Lobe`]), then splits about m:
//! reflection weighted F(m) G1(r), refraction (1 - F(m)) G1(t), Smith's estimator for a
//! visible-normal sample (Heitz 2014). Seen from the air, a rough hit also samples the sun's
//! disc (next-event estimation): its direct reflection is weighted by the power heuristic
//! against the reflection's own density, and the reflected ray carries that density so that
//! the sun it finds by itself gets the complementary weight ([`PathVertex::sun_pdf`]).

use std::mem::MaybeUninit;

use glam::Vec3;

use super::counters::Counters;
use super::integrator::{SceneRef, TraceSettings};
use super::interface::{
    SurfacePoint, bend_normal, bend_threshold, exact_surface_point, keep_side, surface_point,
};
use super::microfacet::{Lobe, power_heuristic};
use super::normals::Unresolved;
use super::water::{fresnel, reflect, refract};
use crate::accel::{Hit, Ray};
use crate::color::luminance;
use crate::config::{FilterLobe, WrongSide};
use crate::ocean::slopes::LevelSet;
use crate::rng::Rng;
use crate::sky::SunLight;

/// What one hit does to a path: where it is, which way the medium changes, the attenuation of
/// the segment that reached it, and the two directions leaving it with their weights.
#[derive(Clone, Copy)]
pub(super) struct Scatter {
    pub(super) sp: SurfacePoint,
    pub(super) from_below: bool,
    pub(super) attenuation: Vec3,
    /// The Fresnel reflectance (at the microfacet normal on a rough hit).
    pub(super) fresnel: f32,
    /// `None`: the wrong-side policy ended this branch, or (rough) it left below the resolved
    /// surface, where masking gives it no weight.
    pub(super) reflected: Option<Vec3>,
    /// `None` on total internal reflection; `Some(None)` when the branch ended.
    pub(super) refracted: Option<Option<Vec3>>,
    /// Smith's masking of the reflected and refracted directions (the `smith` lobe), or the
    /// share of the `mapped` lobe that faces the ray when its normal was drawn among those
    /// (under `terminate`); 1 on a smooth hit.
    pub(super) g_reflected: f32,
    pub(super) g_refracted: f32,
    /// The footprint's width at the hit, m: where the rays leaving it start.
    pub(super) width_m: f32,
    /// The reflected ray's density where the sun was sampled here (for the weight of the sun
    /// it finds); 0 where it was not, and the sun is seen at full weight.
    pub(super) sun_pdf: f32,
    /// The sun's sampled direct light: the shadow ray that must reach the sky, and the
    /// radiance it brings (weighted) if it does.
    pub(super) sun: Option<(Ray, Vec3)>,
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
        g_reflected: 1.0,
        g_refracted: 1.0,
        width_m: 0.0,
        sun_pdf: 0.0,
        sun: None,
    };
}

/// What the shading stage knows of a hit besides the hit itself.
#[derive(Clone, Copy)]
pub(super) struct HitShading {
    /// The shading normal, air side up.
    pub(super) normal: Vec3,
    /// The unresolved waves (filtered normals), or none.
    pub(super) rough: Unresolved,
    /// The footprint's width at the hit, m.
    pub(super) width_m: f32,
    /// The surface of the layers' levels the hit lies on (the exact surface).
    pub(super) lod: LevelSet,
    /// The path's segment (its depth) at this hit.
    pub(super) segment: u32,
    /// The two numbers a rough hit draws its normal with, where the camera's sampler
    /// stratified them (a camera ray's first hit); `None`: from the path's `rng`.
    pub(super) draw: Option<[f32; 2]>,
}

impl SceneRef<'_> {
    /// Shading at a hit of a ray travelling along `d` ([`HitShading`] from
    /// [`Self::shading_normals`]): the interface's normals, the Fresnel weight, the reflected
    /// and refracted directions, and on a rough hit the sampled sun. A rough hit draws its
    /// random numbers from `rng` (the path's own); a smooth one draws none. Written into
    /// `out`, the batch's own slot, whose reference it returns: returned by value, or written
    /// over a placeholder, the 156-byte result was copied through `memcpy` calls, 5 to 9 % of
    /// the default scene's trace.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn scatter<'s>(
        &self,
        ray: &Ray,
        hit: &Hit,
        shading: HitShading,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
        out: &'s mut MaybeUninit<Scatter>,
    ) -> &'s mut Scatter {
        let d = Vec3::from(ray.dir);
        let sp = if let Some((ng, error_m)) = self.accel.surface_normal(hit, &shading.lod) {
            exact_surface_point(ray, hit, Vec3::from(ng), error_m)
        } else {
            surface_point(self.accel.mesh(), hit)
        };
        let from_below = d.dot(sp.ng) > 0.0;
        let attenuation = if from_below {
            settings.water.transmittance(hit.t)
        } else {
            Vec3::ONE
        };

        // Shading normal facing the incoming ray, and the geometric one likewise.
        let mut ns = shading.normal;
        let (ng, eta_i, eta_t) = if from_below {
            (-sp.ng, settings.water.ior, 1.0)
        } else {
            (sp.ng, 1.0, settings.water.ior)
        };
        if from_below {
            ns = -ns;
        }
        let s = out.write(Scatter {
            sp,
            from_below,
            attenuation,
            width_m: shading.width_m,
            ..Scatter::NONE
        });
        // The unresolved waves (filtered normals), and for the `mapped` lobe a normal drawn
        // from them by area, as a point of the pixel would have it: their slopes added to the
        // resolved normal's, both measured from the local vertical as the layers' are, and
        // shaded from here on exactly as a mapped normal is.
        let area_lobe = (settings.filter_lobe == FilterLobe::Mapped)
            .then(|| {
                let up = shading.rough.up;
                Lobe::around(if from_below { -up } else { up }, ns, shading.rough.cov)
            })
            .flatten();
        let policy = settings.wrong_side;
        if let Some(lobe) = &area_lobe {
            c.rough_hits += 1;
            let [u1, u2] = shading.draw.unwrap_or_else(|| [rng.f32(), rng.f32()]);
            // Under `terminate` a normal facing away ends both branches: drawn among the facing
            // normals, the branches carry their share instead (the same expected value).
            let facing =
                (policy == WrongSide::Terminate).then(|| lobe.sample_area_facing(d, u1, u2));
            ns = match facing {
                None => lobe.world(lobe.sample_area(u1, u2), false),
                Some(Some((m, share))) => {
                    (s.g_reflected, s.g_refracted) = (share, share);
                    lobe.world(m, false)
                }
                // no normal of the lobe faces the ray: the ray itself stands for one facing
                // away, and the branches end below as theirs do
                Some(None) => d,
            };
        }
        let mut dead = false;
        let mut modified = false;
        if d.dot(ns) >= 0.0 {
            c.backfacing_shading += 1;
            modified = true;
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
            modified |= bent != ns;
            ns = bent;
        }
        if dead {
            c.terminated += 1;
            s.refracted = Some(None);
            // The sun's samples stand for the whole lobe, whose normals that reflect the sun
            // all face the ray: a drawn normal facing away ends its own branches, not them.
            if let Some(lobe) = area_lobe {
                self.sample_sun_area(s, &lobe, d, ng, None, shading, settings, rng, c);
            }
            return s;
        }
        // Around the normal the policy left.
        let smith = (settings.filter_lobe == FilterLobe::Smith)
            .then(|| Lobe::new(ns, shading.rough.cov))
            .flatten();
        let Some(lobe) = smith else {
            s.fresnel = fresnel(-d.dot(ns), eta_i, eta_t);
            let r = reflect(d, ns);
            s.reflected = keep_side(r, ng, true, policy, c);
            s.refracted = refract(d, ns, eta_i / eta_t).map(|t| keep_side(t, ng, false, policy, c));
            if let Some(lobe) = area_lobe {
                // (A reflection the policy mirrored back above the triangle is the folded
                // lobe's, whose density the sun's weight accounts for.)
                let unmodified = s.reflected.filter(|_| !modified);
                self.sample_sun_area(s, &lobe, d, ng, unmodified, shading, settings, rng, c);
            }
            return s;
        };
        self.scatter_smith(s, &lobe, d, ng, (eta_i, eta_t), shading, settings, rng, c);
        s
    }

    /// The `mapped` lobe's sun: the reflection BSDF of normals drawn by area from `lobe` is
    /// F(h) D(h) h.z / (4 wo.h) for the directions whose normal h the wrong-side policy leaves
    /// alone; a reflection below the triangle is mirrored back above it (policies `mirror` and
    /// `flip`), so there the lobe is folded: a direction's density and BSDF are its own plus
    /// its mirror image's. What the policy changes otherwise (a normal facing away, a bent
    /// one) reaches the sky through the BSDF's samples only, at full weight. The reflected ray
    /// `unmodified` (its normal untouched by the policy) carries its density for the weight of
    /// the sun it may meet. Seen from the air only.
    #[allow(clippy::too_many_arguments)]
    fn sample_sun_area(
        &self,
        s: &mut Scatter,
        lobe: &Lobe,
        d: Vec3,
        ng: Vec3,
        unmodified: Option<Vec3>,
        shading: HitShading,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
    ) {
        let Some(sun) = self.sun.as_ref().filter(|_| !s.from_below) else {
            return;
        };
        let (eta_i, eta_t) = (1.0, settings.water.ior);
        let wo = -d;
        let both = shading.segment < settings.branch_depth;
        let policy = settings.wrong_side;
        let folds = matches!(policy, WrongSide::Mirror | WrongSide::Flip);
        // The lowest reflection the policy leaves alone.
        let lowest = if policy == WrongSide::Bend {
            bend_threshold(ng, wo)
        } else {
            0.0
        };
        // (density, BSDF x cosine) of reflecting wo into w by a front-facing normal
        let lobe_at = |w: Vec3| {
            let h = (wo + w).normalize_or_zero();
            let c = wo.dot(h);
            let (hl, below) = lobe.local(h);
            if c <= 0.0 || below {
                return (0.0, 0.0);
            }
            let f = fresnel(c, eta_i, eta_t);
            let density = lobe.d(hl) * hl.z / (4.0 * c);
            (if both { 1.0 } else { f } * density, f * density)
        };
        let at = |w: Vec3| {
            let e = ng.dot(w);
            if e < lowest || e <= 0.0 {
                return (0.0, 0.0);
            }
            let (p, f) = lobe_at(w);
            if folds {
                let (pm, fm) = lobe_at(w - 2.0 * e * ng);
                (p + pm, f + fm)
            } else {
                (p, f)
            }
        };
        let k = sun_samples_here(sun, settings, s.sp.p, lobe, wo, folds.then_some(ng));
        let reflected = unmodified
            .filter(|&r| k > 0 && sun.near(r))
            .map(|r| at(r).0);
        (s.sun, s.sun_pdf) = sample_sun(sun, s.sp, k, reflected, rng, c, at);
    }

    /// The `smith` lobe around the shading normal: a visible microfacet normal, the split about
    /// it weighted by Smith's masking, and the sun sampled against the folded lobe.
    #[allow(clippy::too_many_arguments)]
    fn scatter_smith(
        &self,
        s: &mut Scatter,
        lobe: &Lobe,
        d: Vec3,
        ng: Vec3,
        (eta_i, eta_t): (f32, f32),
        shading: HitShading,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
    ) {
        let policy = settings.wrong_side;
        c.rough_hits += 1;
        let (wo, _) = lobe.local(-d);
        let [u1, u2] = shading.draw.unwrap_or_else(|| [rng.f32(), rng.f32()]);
        let m_local = lobe.sample_visible(wo, u1, u2);
        let m = lobe.world(m_local, false);
        s.fresnel = fresnel(wo.dot(m_local), eta_i, eta_t);
        // Masking: a direction below the resolved surface has no weight.
        let r = reflect(d, m);
        let (r_local, r_below) = lobe.local(r);
        if !r_below {
            s.g_reflected = lobe.g1(r_local);
            s.reflected = keep_side(r, ng, true, policy, c);
        }
        s.refracted = match refract(d, m, eta_i / eta_t) {
            None => None,
            Some(t) => {
                let (t_local, t_below) = lobe.local(t);
                s.g_refracted = lobe.g1(t_local);
                Some(if t_below {
                    keep_side(t, ng, false, policy, c)
                } else {
                    None
                })
            }
        };

        // The sun, seen from the air. The lobe the reflection actually follows is folded: a
        // direction below the triangle is mirrored back above it by the wrong-side policy
        // (but for `terminate`), so both the density of a direction w above the triangle and
        // the BSDF the sun is reflected by are the lobe's at w plus its at w's mirror image.
        // Past `branch_depth` the reflection is followed with probability F: its density
        // carries that factor.
        let Some(sun) = self.sun.as_ref().filter(|_| !s.from_below) else {
            return;
        };
        let both = shading.segment < settings.branch_depth;
        let folds = policy != WrongSide::Terminate;
        let mirror = |w: Vec3| w - 2.0 * w.dot(ng) * ng;
        // (density, BSDF x cosine) of the lobe itself at world direction w
        let lobe_at = |w: Vec3| {
            let (wi, below) = lobe.local(w);
            if below {
                return (0.0, 0.0);
            }
            let h = (wo + wi).normalize_or_zero();
            let f = fresnel(wo.dot(h), eta_i, eta_t);
            let choice = if both { 1.0 } else { f };
            (
                choice * lobe.reflection_pdf(wo, wi),
                lobe.reflection_cos(wo, wi, f),
            )
        };
        let folded_at = |w: Vec3| {
            let (p, f) = lobe_at(w);
            if folds {
                let (pm, fm) = lobe_at(mirror(w));
                (p + pm, f + fm)
            } else {
                (p, f)
            }
        };
        // (Only a reflection that may meet the sun needs its density.)
        let k = sun_samples_here(sun, settings, s.sp.p, lobe, -d, folds.then_some(ng));
        let reflected = s
            .reflected
            .filter(|&w| k > 0 && sun.near(w))
            .map(|w| folded_at(w).0);
        let above = |w: Vec3| {
            if w.dot(ng) <= 0.0 {
                (0.0, 0.0)
            } else {
                folded_at(w)
            }
        };
        (s.sun, s.sun_pdf) = sample_sun(sun, s.sp, k, reflected, rng, c, above);
    }

    /// The radiance `l` a ray from `org` along `d` brings from the sky, with the sun's part
    /// weighted as multiple importance sampling wants when the ray left a rough hit that
    /// sampled the sun (`sun_pdf` > 0: the density with which that hit chose `d`).
    pub(super) fn weigh_sun(&self, org: Vec3, d: Vec3, sun_pdf: f32, l: Vec3) -> Vec3 {
        match &self.sun {
            Some(sun) if sun_pdf > 0.0 => {
                let (p, radiance) = sun.seen(org, d);
                if p == 0.0 {
                    return l;
                }
                l - (1.0 - power_heuristic(sun_pdf, p)) * radiance
            }
            _ => l,
        }
    }
}

/// Most sun samples a rough hit may take (`render.sun_samples`).
pub const MAX_SUN_SAMPLES: u32 = 16;

/// i / golden ratio, modulo 1, for i < [`MAX_SUN_SAMPLES`]: the second coordinate of the sun's
/// points.
const GOLDEN_STEPS: [f32; MAX_SUN_SAMPLES as usize] = {
    let mut steps = [0.0f32; MAX_SUN_SAMPLES as usize];
    let mut i = 0;
    while i < steps.len() {
        let x = i as f64 * 0.618_033_988_749_894_8;
        steps[i] = (x - (x as u64) as f64) as f32;
        i += 1;
    }
    steps
};

/// Where a lobe reflects the sun above e^-9 of its peak density, a rough hit takes
/// `render.sun_samples` of it; the rest of the glitter's edge is a question of effort only.
const MANY_SUN_SAMPLES_EXPONENT: f32 = 9.0;

/// Where it reflects none of the sun above e^-36 of its peak, a rough hit takes no sample of
/// it: its reflected ray then finds the sun at full weight, but only if its normal lies beyond
/// that bound, where a Gaussian slope distribution holds e^-36 (2e-16) of its normals drawn by
/// area (visible normals weigh them by a bounded factor), so no firefly is left for the
/// samples to have caught.
const NO_SUN_SAMPLE_EXPONENT: f32 = 36.0;

/// The sun's samples a rough hit at `p` viewed along `wo` takes: `render.sun_samples` where
/// `lobe` may reflect the sun above e^-9 of its peak ([`Lobe::reach_exponent`], asked of the sun's
/// centre as `p` sees it, and of its mirror image about `fold`, the geometric normal, where the
/// wrong-side policy folds the lobe), none where it reflects none of it above e^-36, one
/// between. A hit's strategies are a function of the hit alone, so its estimate is unbiased
/// for any count, zero included (the reflected ray then weighs the sun it finds fully): the
/// choice moves only the effort. Most rough hits lie far outside the sun's glitter, where a
/// sample costs some 860 instructions to find a density of nothing.
fn sun_samples_here(
    sun: &SunLight,
    settings: &TraceSettings,
    p: Vec3,
    lobe: &Lobe,
    wo: Vec3,
    fold: Option<Vec3>,
) -> u32 {
    let (centre, reach) = (sun.centre_from(p), sun.reach_rad());
    let mut exponent = lobe.reach_exponent(wo, centre, reach);
    if let Some(ng) = fold {
        let mirror = centre - 2.0 * ng.dot(centre) * ng;
        exponent = exponent.min(lobe.reach_exponent(wo, mirror, reach));
    }
    if exponent >= NO_SUN_SAMPLE_EXPONENT {
        return 0;
    }
    // (a scene that skipped validation still gets a count the samples can hold)
    let k = settings.sun_samples.clamp(1, MAX_SUN_SAMPLES);
    if exponent < MANY_SUN_SAMPLES_EXPONENT {
        k
    } else {
        1
    }
}

/// Next-event estimation of the sun at a rough hit at `sp`, `bsdf(w)` giving the reflection's
/// (density, BSDF x cosine) towards direction w: the sun's direct light with the shadow ray
/// that must reach the sky for it to count, and the density the hit's reflected ray carries
/// for the sun it may find (`Scatter::sun_pdf`), from that ray's own density
/// `reflected_density` (`None`: it cannot find the sun, and carries 0, full weight).
///
/// `k` directions over the sun's cone, the points (i / k, i / golden ratio modulo 1) rotated
/// by one random pair (Cranley-Patterson): each is uniform on its own, and together they are
/// stratified along the first coordinate and spread along the second, covering the disc
/// evenly. Each is weighted by the power heuristic against the BSDF's own sample, counting the
/// k sun samples: the BSDF's sample then sees the weight p_bsdf^2 / (p_bsdf^2 + k^2 p_sun^2),
/// for which its density is handed back over k. One of them carries
/// the shadow ray, chosen in proportion to its contribution (its weight times the luminance of
/// its radiance where sampling knew it, a map's sun; the analytic disc is uniform), and the
/// contribution of all of them over its own: resampled importance, unbiased for any choice in
/// proportion to positive numbers, one shadow ray however many samples. With `k` = 1, one
/// sample from the first two random numbers, its weight unscaled; with `k` = 0 none, and the
/// reflected ray carries 0.
fn sample_sun(
    sun: &SunLight,
    sp: SurfacePoint,
    k: u32,
    reflected_density: Option<f32>,
    rng: &mut Rng,
    c: &mut Counters,
    bsdf: impl Fn(Vec3) -> (f32, f32),
) -> (Option<(Ray, Vec3)>, f32) {
    debug_assert!(k <= MAX_SUN_SAMPLES, "{k} sun samples");
    if k == 0 {
        return (None, 0.0);
    }
    c.sun_hits += 1;
    c.sun_samples += u64::from(k);
    let (o1, o2) = (rng.f32(), rng.f32());
    let kf = k as f32;
    // x in [0, 2) wrapped into [0, 1) (`fract` is a libm call)
    let wrap = |x: f32| if x >= 1.0 { x - 1.0 } else { x };
    // (sample, its weight f cos w / p, the choice's measure of it) of the samples that count
    let mut kept = [(None, 0.0f32, 0.0f32); MAX_SUN_SAMPLES as usize];
    let (mut n, mut total) = (0, 0.0f32);
    for i in 0..k {
        let fi = i as f32;
        let (u1, u2) = (wrap(o1 + fi / kf), wrap(o2 + GOLDEN_STEPS[i as usize]));
        let sample = sun.sample(sp.p, u1, u2);
        if sample.pdf == 0.0 {
            continue;
        }
        let (p_bsdf, f_cos) = bsdf(sample.d);
        if f_cos > 0.0 {
            let w = f_cos * power_heuristic(kf * sample.pdf, p_bsdf) / sample.pdf;
            let measure = w * sample
                .known_radiance()
                .map_or(1.0, |l| luminance(l.to_array()));
            if measure > 0.0 {
                kept[n] = (Some(sample), w, measure);
                n += 1;
                total += measure;
            }
        }
    }
    let reflected_pdf = reflected_density.map_or(0.0, |p| p / kf);
    if n == 0 {
        return (None, reflected_pdf);
    }
    let chosen = if n == 1 {
        0
    } else {
        // the first whose running sum passes u x total (the last, should rounding leave none)
        let target = rng.f32() * total;
        let mut sum = 0.0;
        kept[..n]
            .iter()
            .position(|&(_, _, m)| {
                sum += m;
                sum > target
            })
            .unwrap_or(n - 1)
    };
    let (Some(sample), w, measure) = kept[chosen] else {
        unreachable!("kept samples are Some")
    };
    // (with k = 1, total / measure is exactly 1: the one sample's weight, bit for bit)
    let light = sun.radiance(&sample) * (w * (total / (measure * kf)));
    let light = (light != Vec3::ZERO).then(|| (sp.spawn(sample.d), light));
    (light, reflected_pdf)
}

/// A branch leaving a hit: its direction, whether it travels in the water, its weight besides
/// Fresnel's (Smith's masking on a rough hit) and the density the sun it finds is weighed with
/// (`None`: not followed, radiance zero).
pub(super) type Branch = Option<(Vec3, bool, f32, f32)>;

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
    let reflected = s
        .reflected
        .map(|w| (w, s.from_below, s.g_reflected, s.sun_pdf));
    let refracted = |t: Option<Vec3>| t.map(|w| (w, !s.from_below, s.g_refracted, 0.0));
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

#[cfg(test)]
#[path = "bsdf_tests.rs"]
mod tests;
