#!/usr/bin/env bash
# Sets up a fresh machine and runs the main job: the paper's experiments on the
# paper's scene, the built-in empty Cornell box `cornell-empty` (walls and light;
# `--scene cornell` for the box with its blocks). Tables on the terminal; CSV,
# plots and claims.md under bench-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cargo run --release --locked -- bench cornell --n-sweep 1..200 "$@"
