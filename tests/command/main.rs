//! Tests of the `adaptive-pm` binary: each runs the command as a user
//! would and reads its output, exit code and files. One binary of
//! modules; run one with `cargo test --test command shards_cli::`.

#[path = "../common/mod.rs"]
mod common;

mod bench_cornell_cli;
mod cli;
mod hostile_cli;
mod isa_cli;
mod shards_cli;
