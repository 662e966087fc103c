//! The jobs behind the commands, one file each: plain configuration in, a result struct out,
//! no printing (progress bars on stderr aside, when asked for). The command line (`main.rs`)
//! parses flags into these configurations, calls one function and prints the result (its
//! `Display` is the human report, its `Serialize` the `--json` one).
//!
//! Every job returns [`AppError`], which says whether the user's input was at fault (exit code
//! 2) or the run failed (exit code 1).

pub mod bench;
pub mod compare;
#[cfg(feature = "embree")]
pub mod crosscheck;
pub mod frames;
pub mod info;
pub mod mesh;
pub mod ocean;
pub mod passes;
pub mod render;
pub mod sky;
#[cfg(feature = "embree")]
pub mod smoke;
pub mod stress;
pub mod study;

use std::error::Error;

/// The commit of the checkout this binary was built from, as `git describe --always --dirty`
/// reads it now (`-dirty` when that checkout has uncommitted changes), or "unknown" when the
/// checkout or git is not there. Results that will be committed carry it, so that a figure
/// names the code that measured it.
pub fn commit() -> &'static str {
    static COMMIT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    COMMIT.get_or_init(|| {
        std::process::Command::new("git")
            .args(["-C", env!("CARGO_MANIFEST_DIR")])
            .args([
                "describe",
                "--always",
                "--dirty",
                "--abbrev=12",
                "--exclude=*",
            ])
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok())
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "unknown".into())
    })
}

type BoxError = Box<dyn Error + Send + Sync>;

/// What went wrong in a job, classed by who can fix it.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// Bad input: an argument, a scene file, a sky map. Exit code 2.
    #[error(transparent)]
    Input(BoxError),
    /// A failure while running (out of memory, a write that failed, a device error). Exit
    /// code 1.
    #[error(transparent)]
    Run(BoxError),
}

impl AppError {
    /// Bad input described by a message.
    pub fn input(message: impl Into<String>) -> AppError {
        AppError::Input(message.into().into())
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Input(_) => 2,
            AppError::Run(_) => 1,
        }
    }
}

/// Errors in what the user gave: the configuration, the ocean and LOD parameters, input files.
impl From<crate::config::ConfigError> for AppError {
    fn from(e: crate::config::ConfigError) -> AppError {
        AppError::Input(e.into())
    }
}

impl From<crate::lod::LodError> for AppError {
    fn from(e: crate::lod::LodError) -> AppError {
        use crate::lod::LodError;
        match e {
            LodError::Mesh(_) => AppError::Run(e.into()),
            _ => AppError::Input(e.into()),
        }
    }
}

impl From<crate::ocean::OceanError> for AppError {
    fn from(e: crate::ocean::OceanError) -> AppError {
        use crate::ocean::OceanError;
        match e {
            OceanError::Image(_) => AppError::Run(e.into()),
            _ => AppError::Input(e.into()),
        }
    }
}

/// Reading an image is the user's file at fault; writing one is a failure of the run.
impl From<crate::image_io::ImageError> for AppError {
    fn from(e: crate::image_io::ImageError) -> AppError {
        use crate::image_io::ImageError;
        match e {
            ImageError::Write(_) => AppError::Run(e.into()),
            _ => AppError::Input(e.into()),
        }
    }
}

impl From<crate::image_io::WriteError> for AppError {
    fn from(e: crate::image_io::WriteError) -> AppError {
        AppError::Run(e.into())
    }
}

impl From<crate::render::pipeline::RenderError> for AppError {
    fn from(e: crate::render::pipeline::RenderError) -> AppError {
        use crate::render::pipeline::RenderError;
        match e {
            RenderError::Config(e) => e.into(),
            RenderError::Ocean(e) => e.into(),
            RenderError::Lod(e) => e.into(),
            RenderError::Image(e) => e.into(),
            RenderError::NoEmbree
            | RenderError::CameraUnderwater { .. }
            | RenderError::Folded { .. }
            | RenderError::Objects(crate::objects::ObjectError::Mesh { .. }) => {
                AppError::Input(e.into())
            }
            _ => AppError::Run(e.into()),
        }
    }
}

/// The threads a scene's files are encoded on: `render.threads`, as its trace had (0 = all
/// cores), so that a case given one thread keeps to one while it writes.
pub(crate) fn output_pool(threads: usize) -> Result<rayon::ThreadPool, AppError> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?)
}

impl From<rayon::ThreadPoolBuildError> for AppError {
    fn from(e: rayon::ThreadPoolBuildError) -> AppError {
        AppError::Run(e.into())
    }
}

#[cfg(feature = "embree")]
impl From<crate::accel::embree::EmbreeError> for AppError {
    fn from(e: crate::accel::embree::EmbreeError) -> AppError {
        AppError::Run(e.into())
    }
}

/// What a command's result says beside its report. The command line prints these on stderr after
/// the report (with `--json` too), so that stdout holds only the report: notes are worth knowing
/// and nothing is wrong; warnings say that something in the output may be wrong.
pub trait Remarks {
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
}

/// The one note a sea state outside the spectrum models' range gets, from the clauses of
/// [`crate::ocean::Spectrum::range_notes`]; `None` if there are none.
pub fn sea_state_note(clauses: &[String]) -> Option<String> {
    (!clauses.is_empty()).then(|| {
        format!(
            "this sea state lies outside the range the spectrum's models were fitted on, and they extrapolate (the surface is still a valid sea): {}",
            clauses.join("; ")
        )
    })
}

/// "Embree 3.13.5" or "Rust BVH": which structure traced, for the one-line summaries.
pub fn backend_label(embree_version: Option<&str>) -> String {
    embree_version.map_or_else(|| "Rust BVH".to_string(), |v| format!("Embree {v}"))
}

/// `PREFIX` + `ext`: the files of one output set (`out/render` -> `out/render.exr`).
pub fn with_extension(prefix: &std::path::Path, ext: &str) -> std::path::PathBuf {
    let mut p = prefix.as_os_str().to_owned();
    p.push(ext);
    p.into()
}

/// Checks that `prefix` (an `--out PREFIX` that names PREFIX.exr, PREFIX.png, ...) names files,
/// not a folder: `--out DIR/` wrote the hidden files `DIR/.exr`, `DIR/.png`, `DIR/.json`.
pub fn check_prefix(prefix: &std::path::Path) -> Result<(), AppError> {
    let text = prefix.as_os_str().to_string_lossy();
    if text.is_empty() || text.ends_with(std::path::MAIN_SEPARATOR) || prefix.is_dir() {
        return Err(AppError::input(format!(
            "--out {text:?} names a folder; it is a file prefix (PREFIX.exr, PREFIX.png, PREFIX.json), e.g. {}",
            prefix.join("render").display()
        )));
    }
    Ok(())
}

/// Checks, before any work, that the files of an output set can be written: none is a
/// directory, their folder exists (it is created) and takes a new file. Removes the temporary
/// files that killed earlier runs left beside them. A problem is the user's to fix (exit 2).
pub fn check_outputs(paths: &[std::path::PathBuf]) -> Result<(), AppError> {
    for p in paths {
        if p.is_dir() {
            return Err(AppError::input(format!(
                "{} is a directory; choose another output name",
                p.display()
            )));
        }
        let dir = match p.parent().filter(|d| !d.as_os_str().is_empty()) {
            Some(d) => d.to_path_buf(),
            None => std::path::PathBuf::from("."),
        };
        check_output_dir(&dir)?;
        crate::image_io::sweep_stale_temps(p);
    }
    Ok(())
}

/// Checks that `dir` is (or can be made) a folder that takes new files.
pub fn check_output_dir(dir: &std::path::Path) -> Result<(), AppError> {
    let bad = |why: String| AppError::input(format!("cannot write into {}: {why}", dir.display()));
    if dir.exists() && !dir.is_dir() {
        return Err(bad("it is not a directory".into()));
    }
    std::fs::create_dir_all(dir).map_err(|e| bad(e.to_string()))?;
    let probe = dir.join(format!(
        ".vastocean-probe.{}.{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::File::create(&probe).map_err(|e| bad(e.to_string()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}
