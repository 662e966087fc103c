//! Objects on the sea: their meshes (the built-in Wigley ship, or OBJ / PLY files), placed at
//! their world positions on the curved earth, floating on the waves where asked
//! ([`float`]), and gathered into one triangle mesh with its own acceleration structure beside
//! the ocean's (the ocean's tessellation is untouched). The integrator traces both and takes
//! the nearer hit (`crate::render::objects`).

pub mod float;
pub mod instances;
pub mod load;
pub mod mount;
pub mod ship;

use std::path::PathBuf;

use glam::{Affine3A, DMat3, DVec3, Mat3, Vec3};
use thiserror::Error;

use crate::accel::{Hit, Ray};
use crate::config::{Backend, ObjectConfig};
use crate::lod::curved_frame_position;
use crate::mesh::Mesh;
use crate::ocean::Sampler;
use crate::render::aov::AovLayers;
use float::Plane;
pub use instances::{Instance, InstanceAccel, Prototype};

#[derive(Debug, Error)]
pub enum ObjectError {
    #[error("object mesh {}: {message}", path.display())]
    Mesh { path: PathBuf, message: String },
    #[error("camera.mount names {0:?}, and no [[object]] is called that")]
    Mount(String),
    #[error("the objects' {backend} acceleration structure: {message}")]
    Accel {
        backend: &'static str,
        message: String,
    },
}

/// A mesh in its object's frame (m; bow +x, up +y, design waterline y = 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LocalMesh {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Parts with their own reflectance: triangles from `.0` on (to the next part) take `.1`
    /// instead of the object's `albedo` (the built-in ship's deckhouse).
    pub parts: Vec<(usize, [f64; 3])>,
}

impl LocalMesh {
    /// At least one triangle, finite positions, indices within them.
    pub fn check(&self) -> Result<(), String> {
        if self.triangles.is_empty() {
            return Err("holds no triangle".into());
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!("vertex {i} is not finite: {:?}", self.positions[i]));
        }
        let n = self.positions.len();
        if let Some((t, &i)) = self
            .triangles
            .iter()
            .enumerate()
            .find_map(|(t, tri)| tri.iter().find(|&&i| i as usize >= n).map(|i| (t, i)))
        {
            return Err(format!(
                "triangle {t} names vertex {i}, and the mesh has {n} vertices"
            ));
        }
        Ok(())
    }

    /// The mesh an object's configuration names.
    pub fn of(cfg: &ObjectConfig) -> Result<LocalMesh, ObjectError> {
        if cfg.is_built_in_ship() {
            Ok(ship::wigley_ship(&cfg.ship))
        } else {
            load::read_mesh(&cfg.mesh)
        }
    }
}

/// How an object lies at the render's time: on the sea's plane under it (floating) or level at
/// its `height_m`, turned to its heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// The sea's plane under it (floating objects; `None` for fixed ones).
    pub plane: Option<Plane>,
    /// Its axes (forward, up, starboard) in its unturned frame.
    rotation: DMat3,
    /// Its origin's height above mean sea level, m.
    pub lift: f64,
    sin_heading: f64,
    cos_heading: f64,
}

impl Pose {
    /// The pose of the object `cfg` with mesh `local` on the sea of `sampler`, its origin at
    /// camera-relative `rel` (x, z), m.
    pub fn of(cfg: &ObjectConfig, local: &LocalMesh, sampler: &Sampler, rel: [f64; 2]) -> Pose {
        let (sin_heading, cos_heading) = cfg.heading_deg.to_radians().sin_cos();
        let mut pose = Pose {
            plane: None,
            rotation: DMat3::IDENTITY,
            lift: cfg.height_m,
            sin_heading,
            cos_heading,
        };
        if cfg.float {
            let points = float::waterplane_points(local, cfg.scale);
            let heights: Vec<f64> = points
                .iter()
                .map(|p| {
                    let d = pose.turn(DVec3::new(p[0], 0.0, p[1]));
                    surface_height_at(sampler, (rel[0] + d.x) as f32, (rel[1] + d.z) as f32)
                })
                .collect();
            let plane = float::fit_plane(&points, &heights);
            (pose.plane, pose.rotation, pose.lift) = (Some(plane), plane.rotation(), plane.heave);
        }
        pose
    }

    /// A direction of the object's frame (x forward, y up, z starboard) in the scene's local
    /// tangent frame at the object.
    pub fn turn(&self, v: DVec3) -> DVec3 {
        let r = self.rotation * v;
        let (s, c) = (self.sin_heading, self.cos_heading);
        DVec3::new(r.x * c - r.z * s, r.y, r.x * s + r.z * c)
    }

    /// A point of the object's frame, m, as an offset from its origin's place on mean sea
    /// level in the local tangent frame.
    pub fn place(&self, p: DVec3) -> DVec3 {
        self.turn(p) + DVec3::Y * self.lift
    }
}

/// One object as placed for a render.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedObject {
    pub name: String,
    pub material: crate::config::Material,
    /// A metal's or glass's GGX roughness alpha.
    pub roughness: f32,
    /// Glass's index of refraction.
    pub ior: f32,
    /// Its `albedo`, linear RGB.
    pub albedo: Vec3,
    /// The sea's plane under it (floating objects; `None` for fixed ones).
    pub plane: Option<Plane>,
    /// Its mesh's origin in the scene (camera-relative x, z; y above mean sea level), m.
    pub origin: [f64; 3],
    pub triangle_count: u32,
}

/// All objects of a scene: each an instance of a shared mesh ([`instances`]), with the
/// structure that traces them.
pub struct SceneObjects {
    pub prototypes: Vec<Prototype>,
    /// One per object, in `placed`'s order, their triangle ids in ascending ranges.
    pub instances: Vec<Instance>,
    accel: InstanceAccel,
    pub placed: Vec<PlacedObject>,
    /// All instances' bounds: rays that miss them are not traced.
    lo: Vec3,
    hi: Vec3,
    /// Seconds reading, placing and building took.
    pub build_seconds: f64,
}

impl SceneObjects {
    /// Places the objects of `configs` on the sea of `sampler` (camera-relative, camera at
    /// world `camera_m`) and builds their structure with `backend` on `threads` threads
    /// (0 = all): objects with the same mesh file (or ship dimensions) and scale share one
    /// prototype. `None` when there are no objects.
    pub fn build(
        configs: &[ObjectConfig],
        sampler: &Sampler,
        camera_m: [f64; 2],
        earth_radius_m: f64,
        backend: Backend,
        threads: usize,
    ) -> Result<Option<SceneObjects>, ObjectError> {
        if configs.is_empty() {
            return Ok(None);
        }
        let t = std::time::Instant::now();
        let mut prototypes: Vec<Prototype> = Vec::new();
        let mut keys: Vec<(String, LocalMesh)> = Vec::new();
        let (mut instances, mut placed) = (Vec::new(), Vec::with_capacity(configs.len()));
        let mut base = 0u32;
        for (k, cfg) in configs.iter().enumerate() {
            let key = format!(
                "{:?} {:?} {}",
                cfg.mesh,
                cfg.is_built_in_ship().then_some(cfg.ship),
                cfg.scale.to_bits()
            );
            let proto = match keys.iter().position(|(k, _)| *k == key) {
                Some(i) => i,
                None => {
                    let local = LocalMesh::of(cfg)?;
                    prototypes.push(Prototype::of(&local, cfg.scale)?);
                    keys.push((key, local));
                    prototypes.len() - 1
                }
            };
            let local = &keys[proto].1;
            let rel = [
                cfg.position_m[0] - camera_m[0],
                cfg.position_m[1] - camera_m[1],
            ];
            let pose = Pose::of(cfg, local, sampler, rel);
            // the placement is rigid: the images of the origin and the axes give it
            let at = |v: DVec3| {
                let p =
                    curved_frame_position(rel[0], rel[1], pose.place(v).to_array(), earth_radius_m);
                DVec3::from(p)
            };
            let o = at(DVec3::ZERO);
            let axis = |v: DVec3| (at(v) - o).as_vec3();
            let to_scene = Affine3A::from_mat3_translation(
                Mat3::from_cols(axis(DVec3::X), axis(DVec3::Y), axis(DVec3::Z)),
                o.as_vec3(),
            );
            let mesh = &prototypes[proto].mesh;
            instances.push(Instance::new(proto as u32, mesh, to_scene, base));
            let count = mesh.triangle_count() as u32;
            base = base.checked_add(count).ok_or_else(|| ObjectError::Accel {
                backend: "mesh",
                message: "the objects hold more than 2^32 triangles".into(),
            })?;
            placed.push(PlacedObject {
                name: cfg.display_name(k),
                material: cfg.material,
                roughness: cfg.roughness as f32,
                ior: cfg.ior as f32,
                albedo: Vec3::from(cfg.albedo.map(|c| c as f32)),
                plane: pose.plane,
                origin: o.to_array(),
                triangle_count: count,
            });
        }
        let (lo, hi) = (instances.iter()).fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), i: &Instance| (lo.min(i.lo), hi.max(i.hi)),
        );
        let accel = InstanceAccel::build(&prototypes, &instances, backend, threads)?;
        Ok(Some(SceneObjects {
            prototypes,
            instances,
            accel,
            placed,
            lo,
            hi,
            build_seconds: t.elapsed().as_secs_f64(),
        }))
    }

    /// The closest object hit of each ray (`None` where it meets none).
    pub fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.accel.intersect_many(&self.instances, rays, hits);
    }

    /// The closest object hit of `ray`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut hit = [None];
        self.intersect_many(std::slice::from_ref(ray), &mut hit);
        hit[0]
    }

    /// An error the backend reported while tracing, if any.
    pub fn take_error(&self) -> Option<String> {
        self.accel.take_error()
    }

    /// The backend that traces the objects.
    pub fn backend_name(&self) -> &'static str {
        self.accel.name()
    }

    /// The object (an index into `placed`) and its prototype's triangle of triangle id `prim`.
    #[inline]
    pub fn locate(&self, prim: u32) -> (usize, u32) {
        let k = self.instances.partition_point(|i| i.base <= prim) - 1;
        (k, prim - self.instances[k].base)
    }

    /// The object a triangle belongs to.
    pub fn object(&self, prim: u32) -> &PlacedObject {
        &self.placed[self.locate(prim).0]
    }

    /// A triangle's diffuse reflectance (or a metal's F0, glass's transmittance), linear RGB.
    pub fn albedo(&self, prim: u32) -> Vec3 {
        let (k, t) = self.locate(prim);
        let proto = &self.prototypes[self.instances[k].prototype as usize];
        proto.part_albedo[t as usize].unwrap_or(self.placed[k].albedo)
    }

    /// The size of the coordinates a hit on triangle `prim` is computed from (see
    /// [`Instance::error_scale`]).
    pub fn error_scale(&self, prim: u32) -> f32 {
        self.instances[self.locate(prim).0].error_scale
    }

    /// A triangle's corners in the scene.
    pub fn triangle(&self, prim: u32) -> [Vec3; 3] {
        let (k, t) = self.locate(prim);
        let inst = &self.instances[k];
        let mesh = &self.prototypes[inst.prototype as usize].mesh;
        mesh.triangle(t)
            .map(|p| inst.to_scene.transform_point3(Vec3::from(p)))
    }

    /// Every object's triangles in the scene as one mesh, triangle ids as in hits (for
    /// oracles, exports and tests; rendering traces the instances).
    pub fn scene_mesh(&self) -> Mesh {
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for inst in &self.instances {
            let mesh = &self.prototypes[inst.prototype as usize].mesh;
            let first = positions.len() as u32;
            positions.extend(
                mesh.positions()
                    .iter()
                    .map(|p| inst.to_scene.transform_point3(Vec3::from(*p)).to_array()),
            );
            indices.extend(mesh.indices().iter().map(|t| t.map(|i| first + i)));
        }
        Mesh::new(positions, Vec::new(), Vec::new(), indices)
            .expect("the prototypes' meshes were checked")
    }

    /// Whether `ray` may meet an object: it crosses the objects' bounds within its range.
    #[inline]
    pub fn may_hit(&self, ray: &Ray) -> bool {
        let (o, d) = (Vec3::from(ray.org), Vec3::from(ray.dir));
        let inv = d.recip();
        let (t0, t1) = ((self.lo - o) * inv, (self.hi - o) * inv);
        let near = t0.min(t1).max_element().max(ray.tnear);
        let far = t0.max(t1).min_element().min(ray.tfar);
        // NaN (a zero direction component through a slab's plane) counts as a possible hit
        near <= far || near.is_nan() || far.is_nan()
    }
}

/// An object as a render's report gives it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjectReport {
    /// Its value in the `id` layer (its place in the scene file, from 1).
    pub id: u32,
    pub name: String,
    pub triangles: u32,
    /// Its mesh's origin in the scene (camera-relative x, z; y above mean sea level), m.
    pub origin_m: [f64; 3],
    /// Floating: the sea's plane under it as heave (m), pitch (bow up) and roll (starboard
    /// up), degrees; absent for a fixed object.
    pub heave_m: Option<f64>,
    pub pitch_deg: Option<f64>,
    pub roll_deg: Option<f64>,
    /// With an `id` layer: the pixels it covers, `[x_min, y_min, x_max, y_max]` inclusive
    /// (absent when no pixel's centre ray meets it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bbox_px: Option<[usize; 4]>,
}

impl SceneObjects {
    /// Each object's placement, for the render's report.
    pub fn report(&self) -> Vec<ObjectReport> {
        self.report_with(&AovLayers::default(), 1)
    }

    /// [`Self::report`] with each object's bounding box in `aovs`' id layer, if it has one,
    /// over an image `width` pixels wide.
    pub fn report_with(&self, aovs: &AovLayers, width: usize) -> Vec<ObjectReport> {
        let boxes = aovs.bboxes(width, self.placed.len());
        self.placed
            .iter()
            .enumerate()
            .map(|(k, o)| {
                let pose = o.plane.map(|p| (p.heave, p.pitch_roll_deg()));
                ObjectReport {
                    id: k as u32 + 1,
                    name: o.name.clone(),
                    triangles: o.triangle_count,
                    origin_m: o.origin,
                    heave_m: pose.map(|p| p.0),
                    pitch_deg: pose.map(|p| p.1.0),
                    roll_deg: pose.map(|p| p.1.1),
                    bbox_px: boxes.as_ref().and_then(|b| b[k]),
                }
            })
            .collect()
    }
}

impl std::fmt::Display for ObjectReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.origin_m;
        let (id, name, n) = (self.id, &self.name, self.triangles);
        write!(f, "{id} {name} ({n} triangles) at x {x:.1}, z {z:.1} m")?;
        match (self.heave_m, self.pitch_deg, self.roll_deg) {
            (Some(h), Some(p), Some(r)) => write!(
                f,
                ", floating: heave {h:+.2} m, pitch {p:+.2} deg, roll {r:+.2} deg"
            )?,
            _ => write!(f, ", fixed {y:.2} m above the sea")?,
        }
        match self.bbox_px {
            Some([x0, y0, x1, y1]) => write!(f, ", in pixels {x0}..={x1} x {y0}..={y1}"),
            None => Ok(()),
        }
    }
}

/// The height of the sea surface at camera-relative horizontal position (x, z), m: the point
/// whose displaced position lies there (fixed-point iteration on the horizontal displacement,
/// which converges where the surface does not fold), in the local tangent frame.
pub fn surface_height_at(sampler: &Sampler, x: f32, z: f32) -> f64 {
    let (mut u, mut v) = (x, z);
    for _ in 0..16 {
        let s = sampler.sample(u, v);
        let (nu, nv) = (x - s.disp[0], z - s.disp[1]);
        let moved = (nu - u).abs().max((nv - v).abs());
        (u, v) = (nu, nv);
        if moved < 1e-4 {
            break;
        }
    }
    sampler.sample(u, v).height as f64
}
