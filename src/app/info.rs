//! `vastocean info`: what this build has (versions, backends, Embree's ISA and threads).

use std::fmt;

use serde::Serialize;

use super::AppError;

#[derive(Clone, Debug, Serialize)]
pub struct Info {
    pub vastocean: &'static str,
    pub backends: Vec<&'static str>,
    #[cfg(feature = "embree")]
    pub embree: crate::accel::embree::EmbreeInfo,
    pub cores: usize,
}

/// Asks Embree (with `threads`, 0 = all cores) what it runs with. Embree prints that report
/// only on stdout, so call this before printing anything.
#[cfg_attr(not(feature = "embree"), allow(unused_variables))]
pub fn run(threads: usize) -> Result<Info, AppError> {
    Ok(Info {
        vastocean: env!("CARGO_PKG_VERSION"),
        backends: vec![
            #[cfg(feature = "embree")]
            "embree",
            "rust",
        ],
        #[cfg(feature = "embree")]
        embree: crate::accel::embree::describe(threads)?,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
    })
}

impl fmt::Display for Info {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "vastocean {}", self.vastocean)?;
        writeln!(f, "backends:  {}", self.backends.join(", "))?;
        #[cfg(feature = "embree")]
        {
            let e = &self.embree;
            writeln!(
                f,
                "embree:    {} (compiled against {} headers)",
                e.version, e.compiled_against
            )?;
            writeln!(f, "isa:       {}", e.targets)?;
            writeln!(
                f,
                "threads:   {}",
                e.threads.map_or("?".into(), |t| t.to_string())
            )?;
            writeln!(f, "tasking:   {}", e.tasking)?;
        }
        write!(f, "cores:     {}", self.cores)
    }
}
