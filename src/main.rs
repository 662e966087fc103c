//! The `vastocean` command line: parse (clap, in [`cli`]) -> validated job -> `vastocean::app`
//! -> print. Exit codes: 0 success (also when stdout is closed early, as by `| head`), 2 bad
//! input (arguments, configuration, files), 1 failure while running.

mod cli;

use std::io::Write;
use std::process::ExitCode;

use vastocean::app::AppError;

/// Prints a result: pretty JSON with `--json`, else its human report.
fn emit<T: serde::Serialize + std::fmt::Display>(value: &T, json: bool) -> anyhow::Result<()> {
    let text = if json {
        serde_json::to_string_pretty(value)?
    } else {
        value.to_string()
    };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")?;
    out.flush()?;
    Ok(())
}

/// Prints a result as [`emit`] does, then its notes and warnings on stderr.
fn emit_remarked<T>(value: &T, json: bool) -> anyhow::Result<()>
where
    T: serde::Serialize + std::fmt::Display + vastocean::app::Remarks,
{
    emit(value, json)?;
    for n in value.notes() {
        eprintln!("note: {n}");
    }
    for w in value.warnings() {
        eprintln!("warning: {w}");
    }
    Ok(())
}

fn exit_code(e: &anyhow::Error) -> ExitCode {
    if let Some(app) = e.downcast_ref::<AppError>() {
        return ExitCode::from(app.exit_code());
    }
    if e.downcast_ref::<cli::BadInput>().is_some() {
        return ExitCode::from(2);
    }
    ExitCode::from(1)
}

/// `--version`'s text: vastocean's version and the Embree it runs on (the library found at run
/// time, which may differ from the headers it was built with).
fn long_version() -> String {
    let v = env!("CARGO_PKG_VERSION");
    #[cfg(feature = "embree")]
    return match vastocean::accel::embree::versions() {
        Ok((lib, headers)) if lib == headers => format!("{v} (Embree {lib})"),
        Ok((lib, headers)) => format!("{v} (Embree {lib}, built against its {headers} headers)"),
        Err(e) => format!("{v} (Embree unavailable: {e})"),
    };
    #[cfg(not(feature = "embree"))]
    format!("{v} (built without Embree: the pure-Rust BVH only)")
}

fn main() -> ExitCode {
    // Embree is asked for its version only when --version is asked for.
    let asks_version = std::env::args()
        .skip(1)
        .any(|a| a == "--version" || a == "-V");
    let mut command = <cli::Cli as clap::CommandFactory>::command();
    if asks_version {
        command = command.version(&*Box::leak(long_version().into_boxed_str()));
    }
    let args = match <cli::Cli as clap::FromArgMatches>::from_arg_matches(&command.get_matches()) {
        Ok(a) => a,
        Err(e) => e.exit(),
    };
    // Ctrl-C or a polite kill removes the half-written temporary files (an output set being
    // renamed into place is finished first), then exits as shells expect: 130.
    let _ = ctrlc::set_handler(|| {
        let removed = vastocean::image_io::remove_temps();
        // Progress bars leave the cursor mid-line: start a fresh one.
        eprintln!(
            "\ninterrupted: nothing half-written was kept ({removed} temporary file{} removed); finished outputs stay",
            if removed == 1 { "" } else { "s" }
        );
        std::process::exit(130)
    });
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A reader that stopped reading (`vastocean ... | head`) is not a failure.
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            {
                return ExitCode::SUCCESS;
            }
            let mut msg = format!("error: {e}");
            for cause in e.chain().skip(1) {
                msg.push_str(&format!(": {cause}"));
            }
            eprintln!("{msg}");
            exit_code(&e)
        }
    }
}
