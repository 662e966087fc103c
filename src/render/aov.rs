//! Layers for training data (`render.aovs`): what each pixel's centre ray meets first, as
//! further channels of the render's EXR. Depth `Z` (the distance to the hit, m; +inf for the
//! sky), the shading normal `N.X N.Y N.Z` there (for the water the normal mode's at a zero
//! footprint, air side up, so the mapped normal for `filtered`; for an object its triangle's,
//! facing the camera; in the scene's frame, y up at the camera; zero for the sky) and `id`
//! (-1 the sky, 0 the water, k the k-th object of the scene file).
//! One ray per pixel, through its centre, traced as the camera's own rays are: the layers are
//! exact per pixel, not averages over its samples, so ids never blend at an object's edge.
//! Each object's 2-D bounding box comes from the id layer.

use glam::Vec3;
use rayon::prelude::*;

use super::camera::Camera;
use super::integrator::{SceneRef, TraceSettings};
use crate::accel::Ray;
use crate::config::Aov;

/// The layers of one image, row-major; each present when it was asked for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AovLayers {
    pub depth: Option<Vec<f32>>,
    pub normal: Option<[Vec<f32>; 3]>,
    pub id: Option<Vec<f32>>,
}

/// What one pixel's centre ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
struct First {
    depth: f32,
    normal: Vec3,
    id: i32,
}

/// An object's box in the image: the pixels its id covers, inclusive corners
/// `[x_min, y_min, x_max, y_max]`.
pub type BBox = [usize; 4];

impl AovLayers {
    /// The channels to write, with their EXR names.
    pub fn channels(&self) -> Vec<(&'static str, &[f32])> {
        let mut out: Vec<(&'static str, &[f32])> = Vec::new();
        if let Some(z) = &self.depth {
            out.push(("Z", z));
        }
        if let Some([x, y, z]) = &self.normal {
            out.extend([("N.X", &x[..]), ("N.Y", &y[..]), ("N.Z", &z[..])]);
        }
        if let Some(id) = &self.id {
            out.push(("id", id));
        }
        out
    }

    /// Each object's bounding box in the id layer (`None` for one no pixel sees), for
    /// `objects` objects in an image `width` pixels wide; `None` without an id layer.
    pub fn bboxes(&self, width: usize, objects: usize) -> Option<Vec<Option<BBox>>> {
        let id = self.id.as_ref()?;
        let mut boxes: Vec<Option<BBox>> = vec![None; objects];
        for (i, &v) in id.iter().enumerate() {
            let k = v as i64;
            if k >= 1 && (k as usize) <= objects {
                let (x, y) = (i % width, i / width);
                let b = boxes[k as usize - 1].get_or_insert([x, y, x, y]);
                *b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            }
        }
        Some(boxes)
    }
}

impl SceneRef<'_> {
    /// The layers `aovs` asks for, over `camera`'s image from `camera_height_m` up.
    pub fn aov_layers(
        &self,
        camera: &Camera,
        camera_height_m: f32,
        aovs: &[Aov],
        settings: &TraceSettings,
    ) -> AovLayers {
        if aovs.is_empty() {
            return AovLayers::default();
        }
        let (w, h) = (camera.width, camera.height);
        let origin = [0.0, camera_height_m, 0.0];
        let firsts: Vec<First> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let d = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
                self.first_hit(&Ray::new(origin, d.to_array()), settings)
            })
            .collect();
        let channel = |f: &dyn Fn(&First) -> f32| firsts.iter().map(f).collect::<Vec<f32>>();
        AovLayers {
            depth: aovs.contains(&Aov::Depth).then(|| channel(&|p| p.depth)),
            normal: aovs.contains(&Aov::Normal).then(|| {
                [
                    channel(&|p| p.normal.x),
                    channel(&|p| p.normal.y),
                    channel(&|p| p.normal.z),
                ]
            }),
            id: aovs.contains(&Aov::Id).then(|| channel(&|p| p.id as f32)),
        }
    }

    /// The first thing along a camera ray: an object, the water, or the sky.
    fn first_hit(&self, ray: &Ray, settings: &TraceSettings) -> First {
        let d = Vec3::from(ray.dir);
        let object = self.objects.and_then(|o| {
            let h = o.may_hit(ray).then(|| o.intersect(ray))??;
            Some((o, h))
        });
        let mut bounded = *ray;
        if let Some((_, h)) = object {
            bounded.tfar = h.t;
        }
        let facing = |n: Vec3| if n.dot(d) > 0.0 { -n } else { n };
        if let Some(hit) = self.accel.intersect(&bounded)
            && object.is_none_or(|(_, o)| hit.t < o.t)
        {
            // the water's normal stays on its air side, as shading has it
            let n = self.normal_at(&hit, settings.normals);
            return First {
                depth: hit.t * d.length(),
                normal: n,
                id: 0,
            };
        }
        match object {
            Some((o, hit)) => {
                let [p0, p1, p2] = o.triangle(hit.prim);
                First {
                    depth: hit.t * d.length(),
                    normal: facing((p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y)),
                    id: o.locate(hit.prim).0 as i32 + 1,
                }
            }
            None => First {
                depth: f32::INFINITY,
                normal: Vec3::ZERO,
                id: -1,
            },
        }
    }
}
