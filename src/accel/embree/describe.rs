//! What `vastocean info` and `--version` report of Embree: the library's and the headers'
//! versions, and the ISA, targets, threads and tasking of Embree's own verbose banner.

use std::ffi::{CString, c_char};

use serde::Serialize;

use super::device::device_config;
use super::{Device, EmbreeError, ffi};

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

/// The Embree library this process runs on and the headers it was compiled against, e.g.
/// ("4.3.3", "4.3.3"), from a one-thread device (no banner): what `--version` prints.
pub fn versions() -> Result<(String, String), EmbreeError> {
    let version = Device::new(1)?.version();
    // SAFETY: plain value return.
    let c = unsafe { ffi::vo_compiled_version() };
    Ok((version, format!("{}.{}.{}", c.major, c.minor, c.patch)))
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
