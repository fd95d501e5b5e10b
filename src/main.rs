//! The `adaptive-pm` command line.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    // Every rayon pool of the run, the global one included, sizes itself
    // from RAYON_NUM_THREADS: refuse a count the machine cannot hold before
    // any pool starts.
    let checked = adaptive_pm::embree::default_threads().map_err(anyhow::Error::from);
    match checked.and_then(|_| cli::run(args)) {
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
        Some(adaptive_pm::Error::OutOfMemory { .. }) => Some(
            "lower --quality / --n-max, or raise the process's memory limit (ulimit -v) \
             or free memory",
        ),
        _ => None,
    })
}
