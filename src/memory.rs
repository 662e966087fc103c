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

/// Bytes as "1.23 GB".
pub fn gigabytes(b: u64) -> String {
    format!("{:.2} GB", b as f64 / 1e9)
}

/// Maps in the pages of a fresh buffer on every core of the current pool before its first
/// write: Linux's `madvise(MADV_POPULATE_WRITE)` (5.14 and later) on each core's share, one
/// call where each 4 KiB page would have taken a fault of its own. Changes no byte of it.
/// Whether the kernel did so; elsewhere, or on an older kernel, nothing happens and the first
/// writes fault the pages in as they would have.
pub fn prefault<T>(buf: &mut [T]) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::sync::atomic::{AtomicBool, Ordering};
        const PAGE: usize = 4096;
        const MADV_POPULATE_WRITE: i32 = 23;
        unsafe extern "C" {
            fn madvise(addr: *mut std::ffi::c_void, len: usize, advice: i32) -> i32;
        }
        let (start, len) = (buf.as_mut_ptr() as usize, std::mem::size_of_val(buf));
        // whole pages inside the buffer only
        let (first, end) = (start.div_ceil(PAGE) * PAGE, (start + len) / PAGE * PAGE);
        if end <= first {
            return false;
        }
        let share = (end - first)
            .div_ceil(rayon::current_num_threads())
            .div_ceil(PAGE)
            * PAGE;
        let populated = AtomicBool::new(true);
        rayon::scope(|s| {
            for a in (first..end).step_by(share) {
                let populated = &populated;
                s.spawn(move |_| {
                    let b = (a + share).min(end);
                    // SAFETY: [a, b) is whole pages of `buf`, which the caller holds mutably,
                    // and populating a page leaves its bytes as they are.
                    let r =
                        unsafe { madvise(a as *mut std::ffi::c_void, b - a, MADV_POPULATE_WRITE) };
                    if r != 0 {
                        populated.store(false, Ordering::Relaxed);
                    }
                });
            }
        });
        populated.into_inner()
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = buf;
        false
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn this_machine_reports_some_room() {
        let a = super::available_bytes();
        if cfg!(target_os = "linux") {
            let a = a.expect("MemAvailable is always there on Linux");
            assert!(a > 10_000_000, "{a}");
        }
    }

    /// The minor page faults of the calling thread so far.
    #[cfg(target_os = "linux")]
    fn thread_faults() -> u64 {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").expect("procfs");
        // after the command's ")": state is field 3, minflt field 10
        let rest = &stat[stat.rfind(')').expect("comm") + 2..];
        rest.split_whitespace()
            .nth(7)
            .expect("minflt")
            .parse()
            .expect("a count")
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn a_prefaulted_buffer_keeps_its_zeros_and_its_writes_take_no_faults() {
        let pages = 8192; // 32 MiB: past glibc's mmap threshold, so fresh pages
        let mut buf: Vec<u64> = bytemuck::zeroed_vec(pages * 512);
        let populated = super::prefault(&mut buf);
        assert!(buf.iter().all(|&v| v == 0));
        let before = thread_faults();
        for (i, page) in buf.chunks_mut(512).enumerate() {
            page[7] = i as u64;
        }
        let faults = thread_faults() - before;
        assert!(
            buf.chunks(512)
                .enumerate()
                .all(|(i, p)| p[7] == i as u64 && p[8] == 0)
        );
        if populated {
            assert!(
                faults < pages as u64 / 100,
                "{faults} faults on {pages} prefaulted pages"
            );
        }
    }
}
