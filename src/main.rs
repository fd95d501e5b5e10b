//! The `adaptive-pm` command line.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            if let Some(hint) = cli_hint(&e) {
                eprintln!("hint: {hint}");
            }
            std::process::ExitCode::FAILURE
        }
    }
}

/// What the command line adds to a library error: the flag that changes the
/// limit (the library's messages do not know the command line's words).
fn cli_hint(e: &anyhow::Error) -> Option<&'static str> {
    e.chain().find_map(|cause| match cause.downcast_ref() {
        Some(adaptive_pm::Error::Budget { .. }) => {
            Some("raise the memory budget with --budget-mb, or lower --quality / --n-max")
        }
        _ => None,
    })
}
