//! The Embree device: its thread budget, and the callback through which Embree's errors reach
//! Rust.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::ptr::NonNull;
use std::sync::{Arc, Mutex};

use super::{EmbreeError, error_name, ffi};

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
    pub(super) raw: NonNull<c_void>,
    /// Allocated with `Box::into_raw` (its address is Embree's callback argument, so it must
    /// not move or be borrowed mutably), freed in `Drop` after the device is released.
    sink: NonNull<ErrorSink>,
    pub(super) building: Mutex<()>,
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

pub(super) fn device_config(threads: usize) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
