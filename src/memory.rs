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

/// A zeroed buffer of `len` values in its own memory mapping, whose pages the kernel is asked
/// to back with transparent huge pages (2 MiB) before anything touches them. The ocean's fields
/// and FFT planes are hundreds of MB written once: with 4 KiB pages a third of the build went
/// to page faults. The mapping is the buffer's alone: from the allocator, a buffer under its
/// mmap threshold can sit in the heap, and the advice then outlives the buffer (the heap's
/// later small allocations each faulted and cleared a whole 2 MiB page: 0.6 s of a render).
/// Where huge pages are off (`/sys/kernel/mm/transparent_hugepage/enabled` = never) the pages
/// are ordinary ones; off Unix it is a plain vector.
pub struct LargeBuf<T: Zero> {
    #[cfg(unix)]
    ptr: std::ptr::NonNull<T>,
    #[cfg(unix)]
    len: usize,
    #[cfg(not(unix))]
    vec: Vec<T>,
}

// SAFETY: the buffer owns its values as a Vec would.
unsafe impl<T: Zero + Send> Send for LargeBuf<T> {}
unsafe impl<T: Zero + Sync> Sync for LargeBuf<T> {}

impl<T: Zero> LargeBuf<T> {
    /// `len` zeros.
    #[cfg(unix)]
    pub fn zeroed(len: usize) -> LargeBuf<T> {
        let bytes = std::mem::size_of::<T>()
            .checked_mul(len)
            .expect("a buffer that fits in memory");
        if bytes == 0 {
            return LargeBuf {
                ptr: std::ptr::NonNull::dangling(),
                len,
            };
        }
        // SAFETY: an anonymous private mapping of `bytes` is fresh zeroed memory, page-aligned
        // (so aligned for T); all-zero bytes are valid T (`Zero`). The advice only changes how
        // the pages are backed; a refusal (no transparent huge pages) is ignored.
        unsafe {
            let p = libc::mmap(
                std::ptr::null_mut(),
                bytes,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            );
            if p == libc::MAP_FAILED {
                std::alloc::handle_alloc_error(std::alloc::Layout::array::<T>(len).unwrap());
            }
            #[cfg(target_os = "linux")]
            if bytes >= 4 << 20 {
                libc::madvise(p, bytes, libc::MADV_HUGEPAGE);
            }
            LargeBuf {
                ptr: std::ptr::NonNull::new_unchecked(p as *mut T),
                len,
            }
        }
    }

    /// `len` zeros.
    #[cfg(not(unix))]
    pub fn zeroed(len: usize) -> LargeBuf<T> {
        // SAFETY: all-zero bytes are valid T (`Zero`)
        LargeBuf {
            vec: vec![unsafe { std::mem::zeroed() }; len],
        }
    }
}

#[cfg(unix)]
impl<T: Zero> Drop for LargeBuf<T> {
    fn drop(&mut self) {
        let bytes = std::mem::size_of::<T>() * self.len;
        if bytes > 0 {
            // SAFETY: the mapping was made in `zeroed` with this size and is unmapped once.
            unsafe {
                libc::munmap(self.ptr.as_ptr() as *mut libc::c_void, bytes);
            }
        }
    }
}

impl<T: Zero> std::ops::Deref for LargeBuf<T> {
    type Target = [T];
    #[cfg(unix)]
    fn deref(&self) -> &[T] {
        // SAFETY: `len` initialised values live at `ptr` for the buffer's lifetime
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }
    #[cfg(not(unix))]
    fn deref(&self) -> &[T] {
        &self.vec
    }
}

impl<T: Zero> std::ops::DerefMut for LargeBuf<T> {
    #[cfg(unix)]
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as `deref`, and `&mut self` makes the access unique
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
    }
    #[cfg(not(unix))]
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.vec
    }
}

/// Bytes as "1.23 GB".
pub fn gigabytes(b: u64) -> String {
    format!("{:.2} GB", b as f64 / 1e9)
}

#[cfg(test)]
mod tests {
    #[test]
    fn large_buffers_are_zero_and_writable() {
        use super::LargeBuf;
        let mut v = LargeBuf::<[f32; 8]>::zeroed(1 << 20);
        assert_eq!(v.len(), 1 << 20);
        assert!(v.iter().all(|t| *t == [0.0; 8]));
        v[12345][3] = 1.5;
        v[(1 << 20) - 1][7] = 2.0;
        assert_eq!((v[12345][3], v[(1 << 20) - 1][7]), (1.5, 2.0));
        assert_eq!(v.iter().flatten().sum::<f32>(), 3.5);
        assert!(LargeBuf::<f32>::zeroed(5).iter().all(|&x| x == 0.0));
        assert!(LargeBuf::<f32>::zeroed(0).is_empty());
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
