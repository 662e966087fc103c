//! Instancing: every object is an instance of a prototype, a mesh in its own frame (scaled)
//! built once however many objects use it, placed by a rigid transform (the object's heading,
//! its pose on the sea and the earth's curvature at its place). Embree traces them as instance
//! geometries of one scene over child scenes; the Rust backend as a loop over the instances'
//! boxes, each ray moved into a prototype's frame and traced through its BVH. A hit's
//! triangle id is its instance's `base` plus its prototype's triangle.

use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::{LocalMesh, ObjectError};
use crate::accel::{Accel, Hit, Ray, bvh::Bvh};
use crate::config::Backend;
use crate::mesh::Mesh;

/// A mesh the objects share, in its own frame (bow +x, up +y), already scaled.
pub struct Prototype {
    pub mesh: Arc<Mesh>,
    /// Each triangle's own reflectance (a part's, as the ship's deckhouse), or `None` for its
    /// object's `albedo`.
    pub part_albedo: Vec<Option<Vec3>>,
}

impl Prototype {
    /// The prototype of `local` scaled by `scale`.
    pub fn of(local: &LocalMesh, scale: f64) -> Result<Prototype, ObjectError> {
        let positions = (local.positions.iter())
            .map(|p| p.map(|c| (c * scale) as f32))
            .collect();
        let mesh =
            Mesh::new(positions, Vec::new(), Vec::new(), local.triangles.clone()).map_err(|e| {
                ObjectError::Accel {
                    backend: "mesh",
                    message: e.to_string(),
                }
            })?;
        let mut own = None;
        let part_albedo = (0..local.triangles.len())
            .map(|t| {
                if let Some(&(_, a)) = local.parts.iter().rev().find(|(from, _)| *from <= t) {
                    own = Some(Vec3::from(a.map(|c| c as f32)));
                }
                own
            })
            .collect();
        Ok(Prototype {
            mesh: Arc::new(mesh),
            part_albedo,
        })
    }
}

/// One object as an instance of its prototype.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    pub prototype: u32,
    /// Its triangles' ids in hits: `base..base + ` its prototype's count.
    pub base: u32,
    /// From the prototype's frame to the scene's, and back (rigid: distances along a ray are
    /// the same in both).
    pub to_scene: Affine3A,
    pub to_local: Affine3A,
    /// Its bounds in the scene, a hair wider.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Its translation's length plus its prototype's largest coordinate, m: the size of the
    /// numbers a hit on it is computed from, in either frame.
    pub error_scale: f32,
}

impl Instance {
    /// Places `prototype` (with `mesh`) by `to_scene`, its triangle ids from `base`.
    pub fn new(prototype: u32, mesh: &Mesh, to_scene: Affine3A, base: u32) -> Instance {
        let (lo, hi) = mesh.positions().iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let q = to_scene.transform_point3(Vec3::from(*p));
                (lo.min(q), hi.max(q))
            },
        );
        let pad = 1e-3 + 1e-6 * lo.abs().max(hi.abs()).max_element();
        let extent = (mesh.positions().iter())
            .map(|p| Vec3::from(*p).abs().max_element())
            .fold(0.0f32, f32::max);
        Instance {
            prototype,
            base,
            to_scene,
            to_local: to_scene.inverse(),
            lo: lo - pad,
            hi: hi + pad,
            error_scale: Vec3::from(to_scene.translation).length() + extent,
        }
    }

    /// Whether `ray` crosses the bounds within `[tnear, tfar]`.
    #[inline]
    pub fn crossed(&self, ray: &Ray, tfar: f32) -> bool {
        slabs(self.lo, self.hi, ray, tfar)
    }

    /// `ray` in the prototype's frame, with range up to `tfar`.
    #[inline]
    fn local_ray(&self, ray: &Ray, tfar: f32) -> Ray {
        let o = self.to_local.transform_point3(Vec3::from(ray.org));
        let d = self.to_local.transform_vector3(Vec3::from(ray.dir));
        Ray {
            org: o.to_array(),
            tnear: ray.tnear,
            dir: d.to_array(),
            tfar,
        }
    }
}

/// Whether `ray` crosses the box `lo..hi` within `[ray.tnear, tfar]` (a NaN from a zero
/// direction component in a slab's plane counts as crossing).
#[inline]
pub fn slabs(lo: Vec3, hi: Vec3, ray: &Ray, tfar: f32) -> bool {
    let (o, d) = (Vec3::from(ray.org), Vec3::from(ray.dir));
    let inv = d.recip();
    let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
    let near = t0.min(t1).max_element().max(ray.tnear);
    let far = t0.max(t1).min_element().min(tfar);
    near <= far || near.is_nan() || far.is_nan()
}

/// What traces the instances.
pub enum InstanceAccel {
    /// One BVH per prototype.
    Rust(Vec<Bvh>),
    #[cfg(feature = "embree")]
    Embree(crate::accel::embree::Instances),
}

impl InstanceAccel {
    /// The structure `backend` builds over `prototypes` placed by `instances` (`threads`:
    /// Embree's device's).
    #[cfg_attr(not(feature = "embree"), allow(unused_variables))]
    pub fn build(
        prototypes: &[Prototype],
        instances: &[Instance],
        backend: Backend,
        threads: usize,
    ) -> Result<InstanceAccel, ObjectError> {
        match backend {
            Backend::Rust => Ok(InstanceAccel::Rust(
                prototypes
                    .iter()
                    .map(|p| Bvh::build(p.mesh.clone()))
                    .collect(),
            )),
            #[cfg(feature = "embree")]
            Backend::Embree => {
                use crate::accel::embree::{BuildOptions, Device, Instances, Scene};
                let err = |e: crate::accel::embree::EmbreeError| ObjectError::Accel {
                    backend: "embree",
                    message: e.to_string(),
                };
                let device = Device::new(threads).map_err(err)?;
                let children = prototypes
                    .iter()
                    .map(|p| Scene::new(&device, p.mesh.clone(), BuildOptions::default()))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(err)?;
                let placed: Vec<(usize, [f32; 12])> = instances
                    .iter()
                    .map(|i| (i.prototype as usize, column_major(&i.to_scene)))
                    .collect();
                Ok(InstanceAccel::Embree(
                    Instances::new(&device, children, &placed).map_err(err)?,
                ))
            }
            #[cfg(not(feature = "embree"))]
            Backend::Embree => Err(ObjectError::Accel {
                backend: "embree",
                message: "this build has no Embree (built without the `embree` feature)".into(),
            }),
        }
    }

    /// The closest hit of each ray among `instances`, its triangle id `base + prototype's`.
    pub fn intersect_many(&self, instances: &[Instance], rays: &[Ray], hits: &mut [Option<Hit>]) {
        match self {
            InstanceAccel::Rust(bvhs) => {
                for (ray, h) in rays.iter().zip(hits.iter_mut()) {
                    *h = None;
                    if !ray.is_finite() {
                        continue;
                    }
                    let mut tfar = ray.tfar;
                    for inst in instances {
                        if !inst.crossed(ray, tfar) {
                            continue;
                        }
                        let local = inst.local_ray(ray, tfar);
                        if let Some(hit) = bvhs[inst.prototype as usize].intersect(&local)
                            && hit.t <= tfar
                        {
                            tfar = hit.t;
                            *h = Some(Hit {
                                prim: inst.base + hit.prim,
                                ..hit
                            });
                        }
                    }
                }
            }
            #[cfg(feature = "embree")]
            InstanceAccel::Embree(scene) => {
                const CHUNK: usize = 64;
                let mut found = [None; CHUNK];
                for (rs, hs) in rays.chunks(CHUNK).zip(hits.chunks_mut(CHUNK)) {
                    scene.intersect_many(rs, &mut found[..rs.len()]);
                    for (h, f) in hs.iter_mut().zip(&found) {
                        *h = f.map(|(hit, inst)| Hit {
                            prim: instances[inst as usize].base + hit.prim,
                            ..hit
                        });
                    }
                }
            }
        }
    }

    /// An error the backend reported while tracing, if any.
    pub fn take_error(&self) -> Option<String> {
        match self {
            InstanceAccel::Rust(_) => None,
            #[cfg(feature = "embree")]
            InstanceAccel::Embree(scene) => scene.take_error(),
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            InstanceAccel::Rust(_) => "rust",
            #[cfg(feature = "embree")]
            InstanceAccel::Embree(_) => "embree",
        }
    }
}

/// An affine transform as Embree's 3x4 column-major matrix: the linear part's three columns,
/// then the translation.
#[cfg(feature = "embree")]
fn column_major(a: &Affine3A) -> [f32; 12] {
    let c = |v: glam::Vec3A| [v.x, v.y, v.z];
    let m = a.matrix3;
    let [x, y, z, w] = [c(m.x_axis), c(m.y_axis), c(m.z_axis), c(a.translation)];
    [
        x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1], z[2], w[0], w[1], w[2],
    ]
}
