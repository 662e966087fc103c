//! How much memory this process may still take: the least of the machine's available memory
//! (`MemAvailable`), the cgroup's limit less its use, and the address-space limit (`ulimit -v`).
//! Jobs estimate what they need before allocating and refuse with the figures rather than abort
//! half way (Linux; elsewhere nothing is known and nothing is refused).

/// Bytes this process can still allocate, if anything limits it.
pub fn available_bytes() -> Option<u64> {
    [mem_available(), cgroup_room(), address_space_room()]
        .into_iter()
        .flatten()
        .min()
}

fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn cgroup_room() -> Option<u64> {
    let read = |f: &str| std::fs::read_to_string(format!("/sys/fs/cgroup/{f}")).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?; // "max" = no limit: None
    let current: u64 = read("memory.current")?.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

fn address_space_room() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    // "Max address space  <soft> <hard> bytes": the soft limit, or "unlimited".
    let soft: u64 = line
        .trim_start_matches("Max address space")
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let vm = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let used_kb: u64 = vm.split_whitespace().nth(1)?.parse().ok()?;
    Some(soft.saturating_sub(used_kb * 1024))
}

/// Types whose all-zero bytes are the value zero.
///
/// # Safety
/// An implementor must be plain data for which every byte being 0 is a valid value.
pub unsafe trait Zero: Copy {}
// SAFETY: IEEE 0.0 is all zero bits; arrays and `repr(C)` pairs of it too.
unsafe impl Zero for f32 {}
unsafe impl<const N: usize> Zero for [f32; N] {}
unsafe impl Zero for rustfft::num_complex::Complex<f32> {}

/// A zeroed vector of `len` values whose pages the kernel is asked to back with transparent
/// huge pages (2 MiB) before anything touches them. The ocean's fields and FFT planes are
/// hundreds of MB written once: with 4 KiB pages a third of the build went to page faults.
/// The memory comes zeroed from the allocator (fresh pages, not written here), so the threads
/// that fill it fault its pages in. Where huge pages are off
/// (`/sys/kernel/mm/transparent_hugepage/enabled` = never) or the system is not Linux, this is
/// a plain zeroed vector.
pub fn large_zeroed<T: Zero>(len: usize) -> Vec<T> {
    let layout = std::alloc::Layout::array::<T>(len).expect("a buffer that fits in memory");
    if layout.size() == 0 {
        return Vec::new();
    }
    // SAFETY: the layout has a non-zero size; all-zero bytes are valid T (`Zero`), so the
    // vector's `len` values are initialised, and it owns the allocation made with its layout.
    unsafe {
        let ptr = std::alloc::alloc_zeroed(layout);
        if ptr.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        advise_huge_pages(ptr as usize, layout.size());
        Vec::from_raw_parts(ptr as *mut T, len, len)
    }
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(start: usize, bytes: usize) {
    const PAGE: usize = 4096;
    const HUGE: usize = 2 << 20;
    if bytes < 2 * HUGE {
        return;
    }
    // madvise wants a page-aligned start; the range may end mid-page
    let aligned = start.next_multiple_of(PAGE);
    let len = (start + bytes).saturating_sub(aligned);
    // SAFETY: the range lies inside this allocation, which nothing has touched yet; the
    // advice changes how its pages are backed, never their contents. A refusal (EINVAL where
    // transparent huge pages are not built in) leaves the ordinary pages, so it is ignored.
    unsafe {
        libc::madvise(aligned as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_start: usize, _bytes: usize) {}

/// Bytes as "1.23 GB".
pub fn gigabytes(b: u64) -> String {
    format!("{:.2} GB", b as f64 / 1e9)
}

#[cfg(test)]
mod tests {
    #[test]
    fn large_zeroed_is_zero_and_writable() {
        let mut v = super::large_zeroed::<[f32; 8]>(1 << 20);
        assert_eq!(v.len(), 1 << 20);
        assert!(v.iter().all(|t| *t == [0.0; 8]));
        v[12345][3] = 1.5;
        v.push([2.0; 8]);
        assert_eq!((v[12345][3], v[1 << 20][0]), (1.5, 2.0));
        assert!(super::large_zeroed::<f32>(5).iter().all(|&x| x == 0.0));
        assert!(super::large_zeroed::<f32>(0).is_empty());
    }

    #[test]
    fn this_machine_reports_some_room() {
        let a = super::available_bytes();
        if cfg!(target_os = "linux") {
            let a = a.expect("MemAvailable is always there on Linux");
            assert!(a > 10_000_000, "{a}");
        }
    }
}
