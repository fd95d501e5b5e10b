#!/usr/bin/env bash
# Builds and runs examples/downstream: a renderer that uses adaptive-pm as a
# library (default features off, features = ["embree", "gltf", "image-io"]), with its scene built
# in code, a stored tracer shared by two threads, its own ray caster (a
# trace and a render), an image written and a glTF scene loaded. Also checks
# the API docs build without a warning for each feature set.
# It exits non-zero when one of its checks fails. Also prints the crates that
# such a user compiles (scripts/count-deps.sh, limit 40) and checks the MSRV.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/count-deps.sh | tail -n 1
./scripts/check-msrv.sh
# The library alone, without Embree, glTF or image files: photon_map, brdf,
# emitter, analysis, scene and engine must build there.
cargo build --locked --lib -p adaptive-pm --no-default-features
# The API docs as a library user reads them, for each feature set a
# renderer might pick: no broken link, no warning.
for features in "" "--no-default-features --features embree" "--no-default-features"; do
  # shellcheck disable=SC2086 # the feature flags are words
  RUSTDOCFLAGS="-D warnings" cargo doc --locked --no-deps -p adaptive-pm $features
done
cargo run --locked --release -p adaptive-pm-downstream
