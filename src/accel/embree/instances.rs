//! A committed Embree scene of instances: each places a committed child scene (one mesh)
//! by an affine transform, so a mesh that appears many times is stored and built once.

use std::ffi::c_void;
use std::ptr::NonNull;
use std::sync::Arc;

use super::scene::new_scene;
use super::{BuildOptions, Device, EmbreeError, Scene, error_name, ffi};
use crate::accel::{Hit, Ray};

/// Instances of child scenes in one committed top-level scene.
pub struct Instances {
    raw: NonNull<c_void>,
    /// The scenes the instances place (kept alive as long as the top-level scene).
    _children: Vec<Scene>,
    device: Arc<Device>,
}

// SAFETY: as for `Scene`: a committed scene is only read, which Embree allows from any number
// of threads at once; the children are committed `Scene`s, themselves `Sync`.
unsafe impl Send for Instances {}
unsafe impl Sync for Instances {}

impl Instances {
    /// The scene whose instance k places `children[placed[k].0]` by the 3x4 column-major
    /// transform `placed[k].1` (child space to scene space); a hit's instance is k.
    pub fn new(
        device: &Arc<Device>,
        children: Vec<Scene>,
        placed: &[(usize, [f32; 12])],
    ) -> Result<Instances, EmbreeError> {
        let _building = device.building.lock().unwrap_or_else(|e| e.into_inner());
        let scene = new_scene(device, BuildOptions::default(), 0)?;
        let release = |e| {
            // SAFETY: scene is live and not yet owned by an Instances value.
            unsafe { ffi::vo_scene_release(scene.as_ptr()) };
            e
        };
        for (k, (child, xfm)) in placed.iter().enumerate() {
            let mut id = 0u32;
            // SAFETY: the device and both scenes are live, the child committed; the child is
            // kept alive by `children` for as long as the returned value holds `scene`.
            let g = unsafe {
                ffi::vo_scene_attach_instance(
                    device.raw.as_ptr(),
                    scene.as_ptr(),
                    children[*child].raw().as_ptr(),
                    xfm.as_ptr(),
                    &mut id,
                )
            };
            device
                .check("rtcAttachGeometry (instance)")
                .map_err(release)?;
            if g.is_null() || id as usize != k {
                return Err(release(EmbreeError::Call {
                    call: "rtcNewGeometry (instance)",
                    code: 1,
                    name: error_name(1),
                    message: format!("instance {k} was attached as geometry {id}"),
                }));
            }
        }
        // SAFETY: scene is live and complete.
        unsafe { ffi::vo_scene_commit(scene.as_ptr()) };
        device
            .check("rtcCommitScene (instances)")
            .map_err(release)?;
        Ok(Instances {
            raw: scene,
            _children: children,
            device: device.clone(),
        })
    }

    /// The closest hit of each ray, with the instance it lies in; rays with a NaN or infinite
    /// component miss.
    pub fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<(Hit, u32)>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        const CHUNK: usize = 64;
        let mut out = [ffi::vo_hit::default(); CHUNK];
        for (rs, hs) in rays.chunks(CHUNK).zip(hits.chunks_mut(CHUNK)) {
            for (r, o) in rs.iter().zip(out.iter_mut()) {
                o.prim = ffi::VO_INVALID_ID;
                if r.is_finite() {
                    // SAFETY: `r` has vo_ray's layout; `o` is a valid out-parameter.
                    unsafe {
                        ffi::vo_intersect1(self.raw.as_ptr(), r as *const Ray as *const _, o)
                    };
                }
            }
            for (h, o) in hs.iter_mut().zip(&out) {
                *h = (o.prim != ffi::VO_INVALID_ID && o.inst != ffi::VO_INVALID_ID).then_some((
                    Hit {
                        t: o.t,
                        prim: o.prim,
                        u: o.u,
                        v: o.v,
                    },
                    o.inst,
                ));
            }
        }
    }

    /// An error the device reported while tracing, if any (clearing it).
    pub fn take_error(&self) -> Option<String> {
        self.device.check("tracing").err().map(|e| e.to_string())
    }
}

impl Drop for Instances {
    fn drop(&mut self) {
        // SAFETY: released once, before the children (dropped after this body) and the device.
        unsafe { ffi::vo_scene_release(self.raw.as_ptr()) }
    }
}
