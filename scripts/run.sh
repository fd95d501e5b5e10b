#!/usr/bin/env bash
# Sets up a fresh machine and runs the main job: the paper's experiments on the
# built-in Cornell box (tables on the terminal; CSV and plots under bench-out/).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cargo run --release --locked -- bench cornell --n-sweep 1..200 "$@"
