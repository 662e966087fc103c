//! `vastocean bench`: the two reports the project exists to give, as files a user can
//! regenerate. [`bvh`]: BVH build time (and trace speed) against triangle count for every
//! backend and build quality, on the project's own ocean meshes. [`accuracy`]: the speed /
//! accuracy frontier of one scene, every configuration's error measured against a converged
//! reference with the noise-corrected estimator of `crate::analysis::error`.

pub mod accuracy;
#[cfg(feature = "embree")]
pub mod bvh;

use crate::config::{LodChoice, LodConfig};

/// A custom doubling tessellation with `near_size_m` triangles at the camera and the paper's
/// 18 m double distance.
pub(crate) fn near_size_lod(near_size_m: f64) -> LodConfig {
    LodConfig {
        preset: LodChoice::Custom,
        near_size_m: Some(near_size_m),
        double_distance_m: Some(18.0),
        ..LodConfig::default()
    }
}

#[cfg_attr(not(feature = "embree"), allow(dead_code))]
/// The near-camera triangle size whose paper-reading tessellation (62 N^2 + 36 N triangles,
/// N = 18 m / size, for a 2 m camera) is closest to `triangles`.
pub(crate) fn near_size_for(triangles: f64) -> f64 {
    let n = (-36.0 + (36.0f64 * 36.0 + 4.0 * 62.0 * triangles).sqrt()) / (2.0 * 62.0);
    18.0 / n.round().max(1.0)
}

/// Line-buffered progress on stderr: a bar on a terminal, plain lines otherwise (a batch job's
/// log).
pub(crate) struct Progress {
    bar: indicatif::ProgressBar,
    plain: bool,
    total: u64,
    done: std::sync::atomic::AtomicU64,
}

impl Progress {
    pub(crate) fn new(shown: bool, total: u64, what: &str) -> Progress {
        use std::io::IsTerminal;
        let plain = shown && !std::io::stderr().is_terminal();
        let bar = if shown && !plain {
            let b = indicatif::ProgressBar::new(total);
            b.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{what} {{bar:30}} {{pos}}/{{len}}  {{elapsed}} (eta {{eta}})  {{msg}}"
                ))
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            b
        } else {
            indicatif::ProgressBar::hidden()
        };
        Progress {
            bar,
            plain,
            total,
            done: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// One step done, `msg` saying what it was.
    pub(crate) fn step(&self, msg: impl Into<String>) {
        let msg = msg.into();
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if self.plain {
            eprintln!("[{done}/{}] {msg}", self.total);
        }
        self.bar.set_message(msg);
        self.bar.inc(1);
    }

    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_size_gives_the_paper_counts() {
        // 62 N^2 + 36 N: N = 600 (3 cm) and N = 20 (90 cm).
        assert!((near_size_for(22_341_600.0) - 0.03).abs() < 1e-12);
        assert!((near_size_for(25_520.0) - 0.9).abs() < 1e-12);
    }
}
