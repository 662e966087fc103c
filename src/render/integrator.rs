//! The Monte Carlo path tracer of paper section 5: camera rays meet the tessellated ocean, and
//! every hit splits into a Fresnel reflection and a refraction (weights F and 1 - F), up to a
//! branching depth past which one of the two is chosen at random with probability F (the
//! estimator stays unbiased). Paths end after `max_segments` segments (the paper: 10). The
//! paths of one pixel's samples are traced together, a stage at a time
//! ([`SceneRef::radiance_batch`]), and each comes out bit for bit as it would alone.
//!
//! The shading normal is the interpolated vertex normal (`vertex`, the paper's "without
//! normal mapping") or, for `mapped` (paper section 4), the ocean normal of eq. 7 recomputed
//! from the layers at the texture coordinate interpolated at the hit and tilted into the
//! curved-earth frame there. A shading normal can disagree with the triangle it shades: face
//! away from the incoming ray, or send the reflected or refracted ray to the wrong side of the
//! geometric surface. [`WrongSide`] chooses what happens then (mirror the direction back, flip
//! the normal, bend it as Cycles and Iray do, or end the branch), and each case is counted.
//!
//! Secondary rays leave the surface offset along the geometric normal by a bound on the hit
//! point's floating-point error, rounded away from the surface (pbrt-v4, section 6.8.6;
//! [`crate::fp::offset_ray_origin`]), not by a fixed epsilon.

use glam::Vec3;
use serde::Serialize;

use super::bsdf::{HitShading, Scatter, branches};
pub use super::counters::Counters;
pub use super::earth_tilt::{tilt_to_earth, tilt_to_earth_many};
use super::footprint;
pub use super::interface::{bend_normal, spawn_ray};
use super::normals::{Footprints, Unresolved};
use super::objects::ObjectScatter;
use super::shortcuts::Untraced;
pub use super::shortcuts::{highest_vertex_y, hit_on_triangle, max_slope};
use super::slots::Slots;
use crate::accel::{Accel, Hit, Ray};
use crate::config::{FilterLobe, NormalMode, SceneConfig, Water, WrongSide};
use crate::objects::SceneObjects;
use crate::ocean::Sampler;
use crate::ocean::slopes::{ALL_WAVES, LevelSet, SurfaceSlopes};
use crate::rng::Rng;
use crate::sky::{Sky, SunLight};

/// Path-tracing settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TraceSettings {
    pub normals: NormalMode,
    /// Most segments (rays) in one path.
    pub max_segments: u32,
    /// Hits up to this depth branch into both reflection and refraction; deeper ones choose one.
    pub branch_depth: u32,
    pub water: Water,
    pub wrong_side: WrongSide,
    /// Radiance a downward ray that never meets the surface again returns: the water's R_rs
    /// times the sky's irradiance (see [`Water::upwelling`]), resolved once per render.
    pub upwelling: [f32; 3],
    /// A camera ray with a direction's y below this must meet the sea (it dips under the
    /// horizon of the deepest troughs); one that escapes counts as a hole. -1 = never counted.
    pub must_hit_below_y: f32,
    /// The angle one pixel spans, radians: a camera ray's footprint grows by it per metre
    /// travelled ([`super::footprint`]). Set from the camera by the film; 0 = a footprint of
    /// zero width, under which filtered normals resolve every wave.
    pub pixel_spread_rad: f32,
    /// Filtered normals: the Gaussian footprint's std in cone widths (`render.filter_width`).
    pub filter_width: f32,
    /// Filtered normals: the lobe of the unresolved waves (`render.filter_lobe`).
    pub filter_lobe: FilterLobe,
    /// Rough hits: the sun's samples each takes (`render.sun_samples`).
    pub sun_samples: u32,
}

impl Default for TraceSettings {
    /// The default scene's settings under a sky of irradiance pi (radiance ~1).
    fn default() -> Self {
        TraceSettings::new(&SceneConfig::default(), Vec3::splat(std::f32::consts::PI))
    }
}

impl TraceSettings {
    /// The settings of `scene` under a sky of downwelling irradiance `sky_irradiance`.
    pub fn new(scene: &SceneConfig, sky_irradiance: Vec3) -> TraceSettings {
        TraceSettings {
            normals: scene.render.normals,
            max_segments: scene.render.max_segments,
            branch_depth: scene.render.branch_depth,
            water: scene.water,
            wrong_side: scene.render.wrong_side,
            upwelling: scene.water.upwelling(sky_irradiance).to_array(),
            must_hit_below_y: -1.0,
            pixel_spread_rad: 0.0,
            filter_width: scene.render.filter_width,
            filter_lobe: scene.render.filter_lobe,
            sun_samples: scene.render.sun_samples,
        }
    }
}

/// Most camera rays [`SceneRef::radiance_camera_batch`] takes at once (one pixel's samples go
/// to the BVH together). It bounds every batch of [`SceneRef::radiance_batch`] (a batch holds a
/// sample at most once).
pub const CAMERA_BATCH: usize = 16;

/// What the integrator traces against.
pub struct SceneRef<'a> {
    pub accel: &'a dyn Accel,
    /// From [`max_slope`]: rays in the water descending more steeply than this are not
    /// traced (they cannot hit the surface) and return the upwelling radiance directly; nor are
    /// rays leaving a hit into the air rising more steeply, which see the sky directly; and
    /// camera rays descending more steeply may take a predicted hit (`predict_camera_hits`).
    /// `None` traces every ray.
    pub skip_slope: Option<f32>,
    /// From [`highest_vertex_y`]: rays in the air leaving upwards from above this height are
    /// not traced (nothing lies above it) and see the sky directly. `None` traces every ray.
    pub skip_above_y: Option<f32>,
    /// Camera rays take their hit from their pixel's predicted triangle where that triangle
    /// holds their closest hit ([`SceneRef::predict_camera_prim`]; needs `skip_slope`). The
    /// hits differ from the BVH's by rounding.
    pub predict_camera_hits: bool,
    /// The ocean, for mapped and filtered normals (required for both).
    pub ocean: Option<Sampler<'a>>,
    /// The ocean's slope covariance by band, for filtered normals (without it they resolve
    /// every wave: mapped normals).
    pub slopes: Option<&'a SurfaceSlopes>,
    /// The sky's sun, sampled at rough hits of filtered normals (`None`: found by chance).
    pub sun: Option<SunLight>,
    pub earth_radius_m: f64,
    pub sky: &'a Sky,
    /// Objects on the sea, traced beside it (`None`: the sea alone).
    pub objects: Option<&'a SceneObjects>,
}

impl SceneRef<'_> {
    /// The shading normal `mode` gives at a hit (air side up), for tests and cross-checks.
    pub fn normal_at(&self, hit: &Hit, mode: NormalMode) -> Vec3 {
        self.filtered_normal_at(hit, 0.0, mode).0
    }

    /// The shading normal `mode` gives at a hit whose footprint is `width_m` across, and the
    /// slope covariance filtered normals leave unresolved there (zero for the other modes).
    pub fn filtered_normal_at(
        &self,
        hit: &Hit,
        width_m: f32,
        mode: NormalMode,
    ) -> (Vec3, [f32; 3]) {
        let settings = TraceSettings {
            normals: mode,
            ..TraceSettings::default()
        };
        let (mut n, mut rough) = ([Vec3::Y], [Unresolved::NONE]);
        let c = &mut Counters::default();
        self.shading_normals(
            &[Some(*hit)],
            Footprints::Widths(&[width_m]),
            &settings,
            c,
            &mut n,
            &mut rough,
        );
        (n[0], rough[0].cov)
    }

    /// Radiance arriving at `ray.org` along `-ray.dir`. `in_water`: the ray travels in the sea.
    /// (A batch of one: see [`Self::radiance_batch`].)
    pub fn radiance(
        &self,
        ray: &Ray,
        in_water: bool,
        segment: u32,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
    ) -> Vec3 {
        let vertex = PathVertex {
            ray: *ray,
            sample: 0,
            parent: None,
            in_water,
            in_object: false,
            width_m: 0.0,
            lod: ALL_WAVES,
            sun_pdf: 0.0,
            draw: None,
        };
        let mut out = [Vec3::ZERO];
        self.radiance_batch(
            &[vertex],
            None,
            segment,
            settings,
            std::slice::from_mut(rng),
            c,
            &mut out,
        );
        out[0]
    }

    /// The radiance of up to [`CAMERA_BATCH`] rays at `segment`, each from a different sample
    /// (`rngs[entry.sample]` is its generator), into `out`: the path tracer itself, a stage at a
    /// time over the whole batch, each ray's result bit for bit what it gets in a batch of one.
    ///
    /// The rays the BVH must see are traced together (one call into the backend), every hit is
    /// shaded, and the rays leaving the hits form two
    /// batches of their own: the first branch of every hit (its reflection, or the branch chosen
    /// past `branch_depth`), then the second (its refraction, while both are followed). One
    /// sample's path is a chain of dependent long-latency steps (square roots, divisions, texel
    /// reads); a stage over 16 independent samples lets the processor overlap them. A sample's
    /// subtrees are still finished depth first, first branch before second, whatever else the
    /// batch holds, so its random numbers are drawn in the same order as in a batch of one
    /// (`--pass` renders merge into the single render bit for bit because of this).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn radiance_batch(
        &self,
        entries: &[PathVertex],
        predicted: Option<u32>,
        segment: u32,
        settings: &TraceSettings,
        rngs: &mut [Rng],
        c: &mut Counters,
        out: &mut [Vec3],
    ) {
        debug_assert!(entries.len() <= CAMERA_BATCH && out.len() == entries.len());
        // The objects first: the sea's shortcuts below answer for the sea alone.
        let mut obj_hits = [None; CAMERA_BATCH];
        if let Some(objects) = self.objects
            && segment < settings.max_segments
            && entries.iter().any(|e| objects.may_hit(&e.ray))
        {
            let mut rays = [PathVertex::NONE.ray; CAMERA_BATCH];
            for (r, e) in rays.iter_mut().zip(entries) {
                *r = e.ray;
            }
            let n = entries.len();
            let skip = [false; CAMERA_BATCH];
            self.object_hits(&rays[..n], &skip[..n], &mut obj_hits[..n], c);
        }
        let mut object_entry = [0u8; CAMERA_BATCH];
        let mut n_object = 0;
        // Answered without the BVH, from the sky (all together), or traced together.
        let mut traced = [PathVertex::NONE.ray; CAMERA_BATCH];
        let mut traced_lod = [ALL_WAVES; CAMERA_BATCH];
        let mut traced_entry = [0u8; CAMERA_BATCH];
        let mut m = 0;
        // the entries that see the sky: the untraced ones here, the misses below, looked up
        // together once (the sky's lanes are evaluated in whole chunks)
        let mut sky_entry = Slots::<u8, CAMERA_BATCH>::new();
        for (k, e) in entries.iter().enumerate() {
            let answer = if e.in_object {
                // inside glass: its own surface ahead, or (at the path's end, or through a
                // crack of an open mesh) nothing
                if obj_hits[k].is_none() && segment < settings.max_segments {
                    c.object_leaks += 1;
                }
                Untraced::Known(Vec3::ZERO)
            } else {
                self.answer_untraced(&e.ray, e.in_water, e.parent.is_some(), segment, settings, c)
            };
            match (answer, obj_hits[k]) {
                // the sea cannot be in the way
                (Untraced::Known(_) | Untraced::Sky, Some(_)) => {
                    object_entry[n_object] = k as u8;
                    n_object += 1;
                }
                (Untraced::Known(l), None) => out[k] = l,
                (Untraced::Sky, None) => sky_entry.push(k as u8),
                (Untraced::Trace, object) => {
                    traced[m] = e.ray;
                    traced_lod[m] = e.lod;
                    if let Some(h) = object {
                        // the sea's hit counts only in front of the object's
                        traced[m].tfar = traced[m].tfar.min(h.t);
                    }
                    traced_entry[m] = k as u8;
                    m += 1;
                }
            }
        }
        if m == 0 && n_object == 0 {
            self.sky_along(entries, sky_entry.as_slice(), out);
            return;
        }
        let mut hits = [None; CAMERA_BATCH];
        let exact_lods = self.exact_lods(settings);
        match predicted {
            // (each ray meets its path's surface: every wave's but on the exact surface of a
            // filtered render, and a mesh has only one)
            None => self
                .accel
                .intersect_many_at(&traced[..m], &traced_lod[..m], &mut hits[..m]),
            Some(prim) => {
                // Rays that meet the predicted triangle steeply enough have their hit; the
                // rest go to the BVH together.
                let tri = self.accel.mesh().triangle(prim).map(Vec3::from);
                let mut rest = [PathVertex::NONE.ray; CAMERA_BATCH];
                let mut rest_of = [0u8; CAMERA_BATCH];
                let mut r = 0;
                for (i, ray) in traced[..m].iter().enumerate() {
                    let on_prim = if self.descends_steeply(Vec3::from(ray.dir)) {
                        hit_on_triangle(ray, tri, prim)
                    } else {
                        None
                    };
                    match on_prim {
                        Some(hit) => {
                            c.predicted += 1;
                            hits[i] = Some(hit);
                        }
                        None => {
                            rest[r] = *ray;
                            rest_of[r] = i as u8;
                            r += 1;
                        }
                    }
                }
                let mut rest_hits = [None; CAMERA_BATCH];
                self.accel.intersect_many(&rest[..r], &mut rest_hits[..r]);
                for (&i, h) in rest_of[..r].iter().zip(rest_hits) {
                    hits[i as usize] = h;
                }
            }
        }

        // An object in front of the sea's hit (or with no sea behind it) takes the ray.
        let mut on_object = [false; CAMERA_BATCH];
        for (i, &k) in traced_entry[..m].iter().enumerate() {
            if let Some(oh) = obj_hits[k as usize]
                && hits[i].is_none_or(|h: Hit| h.t >= oh.t)
            {
                (hits[i], on_object[i]) = (None, true);
                object_entry[n_object] = k;
                n_object += 1;
            }
        }

        // Shading at every hit, its normal computed with the others'; what a miss sees.
        let mut widths = [0.0f32; CAMERA_BATCH];
        for ((w, &k), hit) in widths.iter_mut().zip(&traced_entry[..m]).zip(&hits[..m]) {
            if let Some(hit) = hit {
                *w = footprint::width_at(entries[k as usize].width_m, settings, hit.t);
            }
        }
        let mut normals = [Vec3::Y; CAMERA_BATCH];
        let mut rough = [Unresolved::NONE; CAMERA_BATCH];
        self.shading_normals(
            &hits[..m],
            if exact_lods {
                Footprints::Levels(&traced_lod[..m])
            } else {
                Footprints::Widths(&widths[..m])
            },
            settings,
            c,
            &mut normals[..m],
            &mut rough[..m],
        );
        // the shaded hits' entries, and their scattering, written in place by `scatter`
        let mut shaded_k = Slots::<u8, CAMERA_BATCH>::new();
        let mut shaded = Slots::<Scatter, CAMERA_BATCH>::new();
        for (i, (&k, hit)) in traced_entry[..m].iter().zip(&hits[..m]).enumerate() {
            let e = &entries[k as usize];
            match hit {
                None if on_object[i] => {}
                None => match self.miss(&e.ray, e.in_water, segment, settings, c) {
                    Some(l) => {
                        out[k as usize] =
                            self.weigh_sun(e.ray.org.into(), e.ray.dir.into(), e.sun_pdf, l)
                    }
                    None => sky_entry.push(k),
                },
                Some(hit) => {
                    c.hits += 1;
                    // A planar triangle cannot meet a ray leaving it twice: this is rounding.
                    // A ray leaving the exact surface may meet its prism again (the next
                    // wave), but not within a tenth of a millimetre of where it left.
                    c.self_hits += u64::from(if self.accel.exact_surface() {
                        e.parent.is_some() && hit.t * Vec3::from(e.ray.dir).length() < 1e-4
                    } else {
                        e.parent == Some(hit.prim)
                    });
                    let shading = HitShading {
                        normal: normals[i],
                        rough: rough[i],
                        width_m: widths[i],
                        lod: e.lod,
                        segment,
                        draw: e.draw,
                    };
                    let rng = &mut rngs[e.sample as usize];
                    shaded_k.push(k);
                    shaded.push_with(|slot| {
                        self.scatter(&e.ray, hit, shading, settings, rng, c, slot)
                    });
                }
            }
        }
        self.sky_along(entries, sky_entry.as_slice(), out);
        let (shaded_k, shaded) = (shaded_k.as_slice(), shaded.as_slice());
        let n_shaded = shaded.len();
        let mut objects = Slots::<(u8, ObjectScatter), CAMERA_BATCH>::new();
        for &k in &object_entry[..n_object] {
            let e = &entries[k as usize];
            let hit = obj_hits[k as usize].expect("an object entry has its hit");
            let width = footprint::width_at(e.width_m, settings, hit.t);
            let rng = &mut rngs[e.sample as usize];
            objects.push((
                k,
                self.scatter_object(
                    &e.ray,
                    &hit,
                    e.in_water,
                    e.in_object,
                    width,
                    settings,
                    rng,
                    c,
                ),
            ));
        }
        let objects = objects.as_slice();
        // Nodes 0..n_shaded are the sea's hits, the objects' follow.
        let mut suns = [None; CAMERA_BATCH];
        for (sun, s) in suns.iter_mut().zip(shaded.iter().map(|s| s.sun)) {
            *sun = s;
        }
        for (sun, (_, o)) in suns[n_shaded..].iter_mut().zip(objects) {
            *sun = o.sun;
        }
        let mut sun_lods = [ALL_WAVES; CAMERA_BATCH];
        for (lod, k) in sun_lods
            .iter_mut()
            .zip(shaded_k.iter().chain(objects.iter().map(|o| &o.0)))
        {
            *lod = entries[*k as usize].lod;
        }
        let direct = self.sun_through(
            &suns[..n_shaded + n_object],
            &sun_lods[..n_shaded + n_object],
            c,
        );

        // The branches: which each hit follows (drawing a sample's random choice here, before
        // its subtrees), then each batch of branches in turn.
        let mut first = [None; CAMERA_BATCH];
        let mut second = [None; CAMERA_BATCH];
        let mut both = [false; CAMERA_BATCH];
        for (j, (k, s)) in shaded_k.iter().zip(shaded).enumerate() {
            let rng = &mut rngs[entries[*k as usize].sample as usize];
            (first[j], second[j], both[j]) = branches(s, segment, settings, rng);
        }
        let mut l_first = [Vec3::ZERO; CAMERA_BATCH];
        let mut l_second = [Vec3::ZERO; CAMERA_BATCH];
        for (pass, (dirs, l)) in [(&first, &mut l_first), (&second, &mut l_second)]
            .into_iter()
            .enumerate()
        {
            let mut batch = [PathVertex::NONE; CAMERA_BATCH];
            let mut of = [0u8; CAMERA_BATCH];
            let mut b = 0;
            // an object's bounce rides with the first branches
            for (jo, (k, o)) in objects.iter().enumerate().filter(|_| pass == 0) {
                let Some(bounce) = o.bounce else {
                    continue;
                };
                batch[b] = PathVertex {
                    ray: o.sp.spawn(bounce.dir),
                    sample: entries[*k as usize].sample,
                    parent: None,
                    in_water: bounce.in_water,
                    in_object: bounce.in_object,
                    width_m: o.width_m,
                    lod: entries[*k as usize].lod,
                    sun_pdf: bounce.sun_pdf,
                    draw: None,
                };
                of[b] = (n_shaded + jo) as u8;
                b += 1;
            }
            for (j, (k, s)) in shaded_k.iter().zip(shaded).enumerate() {
                if let Some((w, in_water, _, sun_pdf)) = dirs[j] {
                    batch[b] = PathVertex {
                        ray: s.sp.spawn(w),
                        sample: entries[*k as usize].sample,
                        parent: Some(s.sp.prim),
                        in_water,
                        in_object: false,
                        width_m: s.width_m,
                        lod: entries[*k as usize].lod,
                        sun_pdf,
                        draw: None,
                    };
                    of[b] = j as u8;
                    b += 1;
                }
            }
            if b > 0 {
                let mut lb = [Vec3::ZERO; CAMERA_BATCH];
                self.radiance_batch(
                    &batch[..b],
                    None,
                    segment + 1,
                    settings,
                    rngs,
                    c,
                    &mut lb[..b],
                );
                // (by reference: the array by value is a 192-byte memcpy)
                for (&j, &lb) in of[..b].iter().zip(&lb) {
                    let masking = dirs[j as usize].map_or(1.0, |b| b.2);
                    l[j as usize] = masking * lb;
                }
            }
        }
        for (j, (k, s)) in shaded_k.iter().zip(shaded).enumerate() {
            let l = if both[j] {
                s.fresnel * l_first[j] + (1.0 - s.fresnel) * l_second[j]
            } else {
                l_first[j]
            };
            out[*k as usize] = s.attenuation * (l + direct[j]);
        }
        for (jo, (k, o)) in objects.iter().enumerate() {
            let j = n_shaded + jo;
            out[*k as usize] = o.weight * l_first[j] + o.attenuation * direct[j];
        }
    }
}

/// One ray of a batch in [`SceneRef::radiance_batch`]: sample `sample`'s ray, spawned on
/// triangle `parent` (none for a camera ray), travelling in the water or the air.
#[derive(Clone, Copy)]
pub(super) struct PathVertex {
    pub(super) ray: Ray,
    sample: u8,
    parent: Option<u32>,
    in_water: bool,
    /// The ray travels inside a glass object, where the sea is not: only objects are traced.
    in_object: bool,
    /// The ray's footprint width at its origin, m (it grows by the pixel's spread per metre).
    width_m: f32,
    /// The surface of the layers' levels the path meets on the exact surface of a filtered
    /// render (drawn for its camera ray: [`SceneRef::camera_lod`]); every wave otherwise.
    lod: LevelSet,
    /// The density with which a rough hit that sampled the sun chose this ray's direction: the
    /// sun the ray sees directly is weighed against the sun's own samples (0: full weight).
    pub(super) sun_pdf: f32,
    /// A camera ray's stratified pair for the draw of its first rough hit's normal
    /// ([`super::strata`]); `None`: the path's own numbers.
    draw: Option<[f32; 2]>,
}

impl PathVertex {
    /// Sample `sample`'s camera ray, whose path meets the surface `lod`, and whose first rough
    /// hit draws its normal from `draw` (if given).
    pub(super) fn camera(
        ray: Ray,
        sample: u8,
        lod: LevelSet,
        draw: Option<[f32; 2]>,
    ) -> PathVertex {
        PathVertex {
            ray,
            sample,
            lod,
            draw,
            ..PathVertex::NONE
        }
    }

    pub(super) const NONE: PathVertex = PathVertex {
        ray: Ray {
            org: [0.0; 3],
            tnear: 0.0,
            dir: [0.0, 1.0, 0.0],
            tfar: f32::INFINITY,
        },
        sample: 0,
        parent: None,
        in_water: false,
        in_object: false,
        width_m: 0.0,
        lod: ALL_WAVES,
        sun_pdf: 0.0,
        draw: None,
    };
}
