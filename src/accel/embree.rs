//! Safe layer over Debian's Embree (3.13 or 4.x) through the C shim in `wrapper/`.
//!
//! Ownership: a [`Device`] is shared (`Arc`) by the scenes built on it and released last. A
//! [`Scene`] exists only committed: [`Scene::new`] attaches the mesh, commits (timing the BVH
//! build) and returns a value with no mutating methods, so nothing can change it while it is
//! traced. The scene holds the `Arc<Mesh>` whose buffers Embree shares, which keeps them alive
//! and unmodified for exactly as long as Embree may read them.
//!
//! Errors: Embree reports device errors through a callback into a per-device sink; setup calls
//! (device, attach, commit) check it and turn anything there into an [`EmbreeError`]. Ray
//! queries are never checked per ray, as Embree's documentation advises.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{Accel, Hit, Ray};
use crate::mesh::Mesh;

#[allow(non_camel_case_types, non_upper_case_globals, dead_code, clippy::all)]
mod ffi {
    include!(concat!(env!("OUT_DIR"), "/embree_shim.rs"));
}

// `Ray` is handed to the shim as `vo_ray` without copying; these prove the layouts agree.
const _: () = {
    assert!(size_of::<Ray>() == size_of::<ffi::vo_ray>());
    assert!(align_of::<Ray>() == align_of::<ffi::vo_ray>());
    assert!(std::mem::offset_of!(Ray, tnear) == std::mem::offset_of!(ffi::vo_ray, tnear));
    assert!(std::mem::offset_of!(Ray, dir) == std::mem::offset_of!(ffi::vo_ray, dir));
    assert!(std::mem::offset_of!(Ray, tfar) == std::mem::offset_of!(ffi::vo_ray, tfar));
};

#[derive(Debug, Error)]
pub enum EmbreeError {
    #[error("could not create an Embree device with config {config:?}: {message}")]
    Device { config: String, message: String },
    #[error("Embree reported {name} (code {code}) during {call}: {message}")]
    Call {
        call: &'static str,
        code: i32,
        name: &'static str,
        message: String,
    },
    #[error("the mesh's buffers are not padded for Embree's 16-byte vertex loads")]
    Unpadded,
    #[error("the mesh has {0} triangles; Embree's index buffer holds at most 2^32-1")]
    TooLarge(usize),
    #[error("the scene's mesh is shared, so its vertices cannot move")]
    Shared,
    #[error("the moved mesh is invalid: {0}")]
    Mesh(String),
}

fn error_name(code: i32) -> &'static str {
    match code {
        0 => "RTC_ERROR_NONE",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        _ => "RTC_ERROR_UNKNOWN",
    }
}

/// BVH build quality (Embree's RTCBuildQuality). `Refit` applies to the geometry: the scene is
/// then built at low quality, as the two-level structure in which Embree honours a geometry's
/// own quality, and [`Scene::refit`] refits the geometry's BVH instead of rebuilding it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    Low,
    #[default]
    Medium,
    High,
    Refit,
}

crate::config::choice!(Quality { Low => "low", Medium => "medium", High => "high", Refit => "refit" });

impl Quality {
    fn raw(self) -> ffi::vo_quality {
        match self {
            Quality::Low => ffi::VO_QUALITY_LOW,
            Quality::Medium => ffi::VO_QUALITY_MEDIUM,
            Quality::High => ffi::VO_QUALITY_HIGH,
            Quality::Refit => ffi::VO_QUALITY_REFIT,
        }
    }
}

/// How a scene is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildOptions {
    pub quality: Quality,
    /// Smaller BVH nodes, somewhat slower traversal (`RTC_SCENE_FLAG_COMPACT`; the default:
    /// paper-high's render peak 3.15 -> 2.22 GB and its build 6.1 -> 4.6 s for 3-5 % slower
    /// tracing, README "Performance").
    pub compact: bool,
    /// Watertight traversal: a ray through a shared edge hits exactly one triangle.
    pub robust: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            quality: Quality::Medium,
            compact: true,
            robust: true,
        }
    }
}

type ErrorSink = Mutex<Vec<(i32, String)>>;

unsafe extern "C" fn on_error(user: *mut c_void, code: c_int, message: *const c_char) {
    // SAFETY: `user` is the sink `Device` allocated with `Box::into_raw` and frees only after
    // the device is released, and only ever shared (the Mutex serialises access); `message` is
    // a NUL-terminated string owned by Embree for the duration of the call.
    let sink = unsafe { &*(user as *const ErrorSink) };
    let text = if message.is_null() {
        String::new()
    } else {
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    if let Ok(mut v) = sink.lock() {
        v.push((code, text));
    }
}

/// An Embree device with a thread budget.
///
/// Device errors arrive through a callback into a sink the device owns; setup calls drain it
/// and turn what they find into an [`EmbreeError`]. A scene build holds `building` from attach
/// to commit, so two builds on one device cannot report (and consume) each other's errors.
pub struct Device {
    raw: NonNull<c_void>,
    /// Allocated with `Box::into_raw` (its address is Embree's callback argument, so it must
    /// not move or be borrowed mutably), freed in `Drop` after the device is released.
    sink: NonNull<ErrorSink>,
    building: Mutex<()>,
    threads: usize,
}

// SAFETY: Embree's device API is thread safe (its documentation: all calls are, except
// concurrent modification of one scene, which `Scene` rules out). The error sink is a Mutex.
unsafe impl Send for Device {}
unsafe impl Sync for Device {}

impl Device {
    /// Creates a device that uses `threads` threads for BVH builds (0 = all cores).
    pub fn new(threads: usize) -> Result<Arc<Device>, EmbreeError> {
        Device::with_config(threads, "")
    }

    /// As [`Device::new`], with more of Embree's device settings (`rtcNewDevice`'s config
    /// string, e.g. `"max_isa=avx2"` to use no kernels past AVX2, as on a machine without
    /// AVX-512). Embree ignores settings it does not know.
    pub fn with_config(threads: usize, extra: &str) -> Result<Arc<Device>, EmbreeError> {
        let config = match (device_config(threads), extra) {
            (c, "") => c,
            (c, e) if c.is_empty() => e.to_string(),
            (c, e) => format!("{c},{e}"),
        };
        let sink = NonNull::from(Box::leak(Box::<ErrorSink>::default()));
        let c = CString::new(config.clone()).expect("config has no NUL");
        // SAFETY: the callback and its user pointer (the sink) outlive the device (freed in Drop
        // after the release, or just below if there is no device).
        let raw = unsafe { ffi::vo_device_new(c.as_ptr(), Some(on_error), sink.as_ptr().cast()) };
        let Some(raw) = NonNull::new(raw) else {
            // SAFETY: no device holds the pointer; this is the only owner.
            let errors = unsafe { Box::from_raw(sink.as_ptr()) };
            let message = errors
                .lock()
                .ok()
                .and_then(|v| v.last().map(|e| e.1.clone()))
                .unwrap_or_default();
            return Err(EmbreeError::Device { config, message });
        };
        Ok(Arc::new(Device {
            raw,
            sink,
            building: Mutex::new(()),
            threads,
        }))
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Bytes Embree holds for this device now, and the most it has held since it was created
    /// (its memory monitor; builds on other threads included).
    pub fn memory(&self) -> (u64, u64) {
        let (mut now, mut peak) = (0i64, 0i64);
        // SAFETY: raw is a live device; the out-parameters are valid.
        unsafe { ffi::vo_device_memory(self.raw.as_ptr(), &mut now, &mut peak) };
        (now.max(0) as u64, peak.max(0) as u64)
    }

    /// The Embree version of the loaded library, e.g. "3.13.5".
    pub fn version(&self) -> String {
        // SAFETY: raw is a live device.
        let v = unsafe { ffi::vo_device_version(self.raw.as_ptr()) };
        format!("{}.{}.{}", v.major, v.minor, v.patch)
    }

    /// Turns a pending device error after `call` into an `Err`, clearing it.
    pub fn check(&self, call: &'static str) -> Result<(), EmbreeError> {
        // SAFETY: raw is a live device.
        let code = unsafe { ffi::vo_device_take_error(self.raw.as_ptr()) };
        // SAFETY: the sink lives as long as self and is only ever shared.
        let sink = unsafe { self.sink.as_ref() };
        let logged = std::mem::take(&mut *sink.lock().unwrap_or_else(|e| e.into_inner()));
        // The first logged error is the root cause; later ones are usually its consequences.
        let (code, message) = match logged.split_first() {
            None if code == 0 => return Ok(()),
            None => (code, String::new()),
            Some(((c, m), [])) => (*c, m.clone()),
            Some(((c, m), rest)) => {
                let more: Vec<&str> = rest.iter().map(|r| r.1.as_str()).collect();
                (*c, format!("{m} (then: {})", more.join("; ")))
            }
        };
        Err(EmbreeError::Call {
            call,
            code,
            name: error_name(code),
            message,
        })
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every Scene holds an Arc<Device>, so no scene outlives this release. After
        // it Embree calls the error callback no more, so the sink can go.
        unsafe {
            ffi::vo_device_release(self.raw.as_ptr());
            drop(Box::from_raw(self.sink.as_ptr()));
        }
    }
}

fn device_config(threads: usize) -> String {
    if threads == 0 {
        String::new()
    } else {
        format!("threads={threads}")
    }
}

/// Sets flush-to-zero / denormals-are-zero on the calling thread (see DESIGN.md, Parallelism).
pub fn flush_denormals_on_this_thread() {
    // SAFETY: only changes this thread's MXCSR denormal bits.
    unsafe { ffi::vo_flush_denormals() }
}

/// A committed Embree scene holding one triangle mesh.
pub struct Scene {
    raw: NonNull<c_void>,
    geometry: NonNull<c_void>,
    mesh: Arc<Mesh>,
    build_seconds: f64,
    options: BuildOptions,
    device: Arc<Device>,
    /// Rays with a NaN or infinite origin or direction, answered as misses without Embree.
    rejected: AtomicU64,
    /// What the device's memory monitor saw the build allocate (the BVH and Embree's own
    /// per-geometry data; the shared mesh buffers are not copied).
    bytes: u64,
}

// SAFETY: a committed scene is only read (rtcIntersect*, rtcOccluded*, rtcInterpolate), which
// Embree allows from any number of threads at once; `Scene` has no method that modifies it,
// and the shared mesh buffers are immutable behind the Arc.
unsafe impl Send for Scene {}
unsafe impl Sync for Scene {}

impl Scene {
    /// Attaches `mesh`, builds the BVH and returns the committed scene.
    pub fn new(
        device: &Arc<Device>,
        mesh: Arc<Mesh>,
        options: BuildOptions,
    ) -> Result<Scene, EmbreeError> {
        if !mesh.is_padded() {
            return Err(EmbreeError::Unpadded);
        }
        if mesh.triangle_count() >= u32::MAX as usize {
            return Err(EmbreeError::TooLarge(mesh.triangle_count()));
        }
        let dev = device.raw.as_ptr();
        // Held from attach to commit: errors drained below are this build's.
        let _building = device.building.lock().unwrap_or_else(|e| e.into_inner());
        let flags = if options.compact {
            ffi::VO_SCENE_COMPACT
        } else {
            0
        } | if options.robust {
            ffi::VO_SCENE_ROBUST
        } else {
            0
        };
        // SAFETY: dev is live; the scene is released in Drop or on the error paths below.
        let scene = unsafe { ffi::vo_scene_new(dev, options.quality.raw(), flags) };
        device.check("rtcNewScene")?;
        let scene = NonNull::new(scene).ok_or(EmbreeError::Call {
            call: "rtcNewScene",
            code: 1,
            name: error_name(1),
            message: "no scene returned".into(),
        })?;
        let release = |e| {
            // SAFETY: scene is live and not yet owned by a Scene value.
            unsafe { ffi::vo_scene_release(scene.as_ptr()) };
            e
        };
        let uvs = if mesh.uvs().is_empty() {
            std::ptr::null()
        } else {
            mesh.uvs().as_ptr() as *const f32
        };
        let mut geom_id = 0u32;
        // SAFETY: buffers are validated (indices in range), padded (checked above) and kept
        // alive and unmodified by the Arc<Mesh> stored in the returned Scene.
        let geometry = unsafe {
            ffi::vo_scene_attach_triangles(
                dev,
                scene.as_ptr(),
                options.quality.raw(),
                mesh.positions().as_ptr() as *const f32,
                mesh.vertex_count(),
                mesh.indices().as_ptr() as *const u32,
                mesh.triangle_count(),
                uvs,
                &mut geom_id,
            )
        };
        device.check("rtcAttachGeometry").map_err(release)?;
        let geometry = NonNull::new(geometry).ok_or_else(|| {
            release(EmbreeError::Call {
                call: "rtcNewGeometry",
                code: 1,
                name: error_name(1),
                message: "no geometry returned".into(),
            })
        })?;
        let before = device.memory().0;
        let start = Instant::now();
        // SAFETY: scene is live and complete.
        unsafe { ffi::vo_scene_commit(scene.as_ptr()) };
        let build_seconds = start.elapsed().as_secs_f64();
        let bytes = device.memory().0.saturating_sub(before);
        device.check("rtcCommitScene").map_err(release)?;
        Ok(Scene {
            raw: scene,
            geometry,
            mesh,
            build_seconds,
            options,
            device: device.clone(),
            rejected: AtomicU64::new(0),
            bytes,
        })
    }

    /// The Embree version of the device this scene was built on.
    pub fn device_version(&self) -> String {
        self.device.version()
    }

    /// Wall-clock seconds the BVH build (rtcCommitScene) took.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    pub fn options(&self) -> BuildOptions {
        self.options
    }

    /// Moves the mesh's vertices to `positions` in place (the topology stays) and updates the
    /// BVH: a refit of its bounds when the scene was built with [`Quality::Refit`], a rebuild
    /// otherwise. Returns the seconds Embree took. Fails without touching anything when
    /// something else still holds the scene's mesh or the positions are invalid.
    pub fn refit(&mut self, positions: &[[f32; 3]]) -> Result<f64, EmbreeError> {
        self.refit_with(|m| m.set_positions(positions))
    }

    /// As [`Scene::refit`], moving the vertex normals too (an animation frame).
    pub fn refit_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<f64, EmbreeError> {
        self.refit_with(|m| m.set_vertices(positions, normals))
    }

    fn refit_with(
        &mut self,
        update: impl FnOnce(&mut Mesh) -> Result<(), crate::mesh::MeshError>,
    ) -> Result<f64, EmbreeError> {
        let mesh = Arc::get_mut(&mut self.mesh).ok_or(EmbreeError::Shared)?;
        update(mesh).map_err(|e| EmbreeError::Mesh(e.to_string()))?;
        let _building = self
            .device
            .building
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let start = Instant::now();
        // SAFETY: the scene and geometry are live; the vertex buffer is the one attached (the
        // Vec was changed in place, never reallocated) and nothing traces while `&mut self`.
        unsafe { ffi::vo_scene_refit(self.raw.as_ptr(), self.geometry.as_ptr()) };
        let seconds = start.elapsed().as_secs_f64();
        self.device.check("rtcCommitScene (refit)")?;
        Ok(seconds)
    }

    /// Axis-aligned bounds of the scene as Embree sees it: (lower, upper).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (mut lo, mut hi) = ([0f32; 3], [0f32; 3]);
        // SAFETY: scene is committed; the arrays have three elements each.
        unsafe { ffi::vo_scene_bounds(self.raw.as_ptr(), lo.as_mut_ptr(), hi.as_mut_ptr()) };
        (lo, hi)
    }

    /// Whether anything lies on the ray within `[tnear, tfar]`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !self.admit(ray) {
            return false;
        }
        // SAFETY: Ray has vo_ray's layout (checked at compile time); scene is committed.
        unsafe {
            ffi::vo_occluded1(self.raw.as_ptr(), ray as *const Ray as *const ffi::vo_ray) != 0
        }
    }
}

impl Scene {
    /// Whether `ray` may be handed to Embree; counts the ones that may not.
    #[inline]
    fn admit(&self, ray: &Ray) -> bool {
        let ok = ray.is_finite();
        if !ok {
            self.rejected.fetch_add(1, Ordering::Relaxed);
        }
        ok
    }
}

fn to_hit(h: &ffi::vo_hit) -> Option<Hit> {
    (h.prim != ffi::VO_INVALID_ID).then_some(Hit {
        t: h.t,
        prim: h.prim,
        u: h.u,
        v: h.v,
    })
}

impl Accel for Scene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.admit(ray) {
            return None;
        }
        let mut h = ffi::vo_hit::default();
        // SAFETY: as in `occluded`; `h` is a valid out-parameter.
        unsafe {
            ffi::vo_intersect1(
                self.raw.as_ptr(),
                ray as *const Ray as *const ffi::vo_ray,
                &mut h,
            )
        };
        to_hit(&h)
    }

    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        // Fixed-size chunks keep the shim's output on the stack: no allocation per batch.
        const CHUNK: usize = 64;
        let mut out = [ffi::vo_hit::default(); CHUNK];
        for (rs, hs) in rays.chunks(CHUNK).zip(hits.chunks_mut(CHUNK)) {
            if !rs.iter().all(Ray::is_finite) {
                // Rare: trace this chunk ray by ray, so the bad rays are answered (and counted)
                // without reaching Embree.
                for (r, h) in rs.iter().zip(hs.iter_mut()) {
                    *h = self.intersect(r);
                }
                continue;
            }
            // SAFETY: `rs` is a slice of vo_ray-layout rays; `out` has room for rs.len() hits.
            unsafe {
                ffi::vo_intersect_batch(
                    self.raw.as_ptr(),
                    rs.as_ptr() as *const ffi::vo_ray,
                    out.as_mut_ptr(),
                    rs.len(),
                )
            };
            for (h, o) in hs.iter_mut().zip(&out) {
                *h = to_hit(o);
            }
        }
    }

    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn interpolate_uv(&self, hit: &Hit) -> [f32; 2] {
        // In Rust from the barycentrics: rtcInterpolate through the shim cost ~157
        // instructions a hit (issue 16's callgrind), this a dozen. A foreign `Hit` must not
        // index outside the buffers.
        let m = &self.mesh;
        match m.indices().get(hit.prim as usize) {
            Some(&tri) if !m.uvs().is_empty() => Mesh::interpolate(m.uvs(), tri, hit.u, hit.v),
            _ => [0.0; 2],
        }
    }

    fn name(&self) -> &'static str {
        "embree"
    }

    fn rejected_rays(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }

    fn bytes(&self) -> u64 {
        self.bytes
    }

    fn update_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<f64, String> {
        self.refit_vertices(positions, normals)
            .map_err(|e| e.to_string())
    }

    fn take_error(&self) -> Option<String> {
        self.device.check("tracing").err().map(|e| e.to_string())
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: the scene (and the geometry it owns) is released once; the device outlives it
        // through `device`.
        unsafe { ffi::vo_scene_release(self.raw.as_ptr()) }
    }
}

/// What Embree says about itself: versions, the ISA it selected and its thread count.
#[derive(Debug, Clone, Serialize)]
pub struct EmbreeInfo {
    pub version: String,
    pub compiled_against: String,
    pub isa: String,
    pub targets: String,
    pub threads: Option<usize>,
    pub tasking: String,
}

/// Probes Embree with `verbose=1` and reads its own report. `threads` as in [`Device::new`].
/// Embree prints that report to stdout only, so the shim redirects file descriptor 1 for the
/// duration of the probe: only `vastocean info` calls this, before it prints anything. (Versions
/// elsewhere come from `rtcGetDeviceProperty`, [`Device::version`].)
pub fn describe(threads: usize) -> Result<EmbreeInfo, EmbreeError> {
    let device = Device::new(threads)?;
    let version = device.version();
    // SAFETY: plain value return.
    let c = unsafe { ffi::vo_compiled_version() };
    let config = CString::new(device_config(threads)).expect("config has no NUL");
    let mut buf = vec![0u8; 16 * 1024];
    // SAFETY: buf is writable for its length; the shim NUL-terminates.
    let n =
        unsafe { ffi::vo_describe(config.as_ptr(), buf.as_mut_ptr() as *mut c_char, buf.len()) };
    let banner = String::from_utf8_lossy(&buf[..n]).into_owned();
    Ok(parse_banner(
        &banner,
        version,
        format!("{}.{}.{}", c.major, c.minor, c.patch),
    ))
}

/// Extracts the fields of Embree's verbose banner. The "Config" block (what this device uses)
/// follows the "CPU" block (what the machine has), so later lines win.
fn parse_banner(banner: &str, version: String, compiled_against: String) -> EmbreeInfo {
    let mut info = EmbreeInfo {
        version,
        compiled_against,
        isa: String::new(),
        targets: String::new(),
        threads: None,
        tasking: String::new(),
    };
    for line in banner.lines() {
        let Some((key, value)) = line.split_once(':') else {
            continue;
        };
        let value = value.trim();
        match key.trim() {
            "ISA" => info.isa = value.to_string(),
            "Targets" => info.targets = value.trim_end_matches("(supported)").trim().to_string(),
            "Threads" => info.threads = value.parse().ok().or(info.threads),
            "Tasking" => info.tasking = value.to_string(),
            _ => {}
        }
    }
    info
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn banner_fields_are_read_from_the_config_block() {
        let banner = "  CPU : x\n   Threads  : 8\n   ISA : SSE AVX2\n  Config\n    Threads : 2\n    ISA     : SSE AVX2\n    Targets : SSE AVX AVX2  (supported)\n              SSE2 AVX512  (compile time enabled)\n    Tasking : TBB2021.5\n";
        let i = parse_banner(banner, "3.13.5".into(), "3.13.5".into());
        assert_eq!(i.threads, Some(2));
        assert_eq!(i.targets, "SSE AVX AVX2");
        assert_eq!(i.tasking, "TBB2021.5");
    }

    #[test]
    fn device_errors_reach_rust_through_the_callback() {
        let device = Device::new(1).unwrap();
        assert!(device.check("nothing").is_ok());
        let floats = [0f32; 16];
        let indices = [0u32, 1, 2];
        // SAFETY: deliberately misaligned (by one byte) but in-bounds pointer: Embree must
        // refuse it with an error, which is what this test provokes.
        unsafe {
            let scene = ffi::vo_scene_new(device.raw.as_ptr(), ffi::VO_QUALITY_MEDIUM, 0);
            let bad = (floats.as_ptr() as *const u8).add(1) as *const f32;
            ffi::vo_scene_attach_triangles(
                device.raw.as_ptr(),
                scene,
                ffi::VO_QUALITY_MEDIUM,
                bad,
                3,
                indices.as_ptr(),
                1,
                std::ptr::null(),
                &mut 0,
            );
            let err = device.check("rtcSetSharedGeometryBuffer").unwrap_err();
            ffi::vo_scene_release(scene);
            match err {
                EmbreeError::Call {
                    code,
                    name,
                    message,
                    ..
                } => {
                    // Embree classes a misaligned buffer as an invalid operation.
                    assert_eq!(
                        (code, name),
                        (3, "RTC_ERROR_INVALID_OPERATION"),
                        "{message}"
                    );
                    assert!(message.contains("align"), "{message}");
                }
                e => panic!("unexpected {e}"),
            }
        }
        assert!(
            device.check("after").is_ok(),
            "errors are consumed once reported"
        );
    }

    #[test]
    fn device_reports_its_version_and_threads() {
        let info = describe(2).unwrap();
        assert!(
            info.version.starts_with('3') || info.version.starts_with('4'),
            "{info:?}"
        );
        assert_eq!(
            info.version.split('.').next(),
            info.compiled_against.split('.').next()
        );
        assert_eq!(info.threads, Some(2));
    }
}
