#!/usr/bin/env bash
# Builds and runs examples/downstream: a renderer that uses adaptive-pm as a
# library (default features off, features = ["embree"]), with its scene built
# in code, a stored tracer shared by two threads and its own ray caster.
# It exits non-zero when one of its checks fails. Also prints the crates that
# such a user compiles (scripts/count-deps.sh, limit 40) and checks the MSRV.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/count-deps.sh | tail -n 1
./scripts/check-msrv.sh
# The library alone, without Embree, glTF or image files: photon_map, brdf,
# emitter, analysis, scene and engine must build there.
cargo build --locked --lib -p adaptive-pm --no-default-features
cargo run --locked --release -p adaptive-pm-downstream
