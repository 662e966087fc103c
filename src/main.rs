//! The `vastocean` command line: parse (clap, in [`cli`]) -> validated job -> `vastocean::app`
//! -> print. Exit codes: 0 success (also when stdout is closed early, as by `| head`), 2 bad
//! input (arguments, configuration, files), 1 failure while running.

mod cli;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;
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

fn exit_code(e: &anyhow::Error) -> ExitCode {
    if let Some(app) = e.downcast_ref::<AppError>() {
        return ExitCode::from(app.exit_code());
    }
    if e.downcast_ref::<cli::BadInput>().is_some() {
        return ExitCode::from(2);
    }
    ExitCode::from(1)
}

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    // Ctrl-C or a polite kill removes the half-written temporary files (an output set being
    // renamed into place is finished first), then exits as shells expect: 130.
    let _ = ctrlc::set_handler(|| vastocean::image_io::remove_temps_and_exit(130));
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
