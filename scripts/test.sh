#!/usr/bin/env bash
# Sets up a fresh machine and runs the whole test suite:
# 1. the unit, integration and doc tests (cargo test);
# 2. the determinism tests once per Embree kernel set the CPU runs, each
#    pinned (scripts/ci-pinned-isa.sh), and a short seed sweep of the
#    statistical tests (scripts/seed-sweep.sh; SEED_SWEEP_N seeds, default 4;
#    the full sweep is `scripts/seed-sweep.sh 32`);
# 2b. the Khronos glTF-Validator over every glTF and GLB file in the
#    repository (scripts/ci-gltf-validator.sh; installs nodejs and npm), and
#    the loader checked against its verdicts (tests/library/gltf_validator.rs),
#    then the same over the glTF documents the tests write at run time
#    (scripts/ci-gltf-validator-generated.sh);
# 3. the packaged crates built as a user gets them (cargo package), so that
#    a file the code embeds cannot be left out of the package;
# 4. the downstream renderer (a library user with default features off), the
#    dependency count and the MSRV check (scripts/ci-downstream.sh);
# 5. a sharded trace on a real single-node Slurm, merged and checked against a
#    single run (scripts/ci-slurm.sh; needs root for its packages and daemons,
#    so it is skipped with a note elsewhere);
# 6. the scene-loading fuzzer for 60 s (scripts/ci-fuzz.sh; needs the nightly
#    toolchain, skipped with a note where there is none).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
stage_start=$SECONDS
cargo test --workspace --locked
echo "test.sh: the cargo test stage took $((SECONDS - stage_start)) s" >&2
bash scripts/ci-pinned-isa.sh
bash scripts/seed-sweep.sh "${SEED_SWEEP_N:-4}"
bash scripts/ci-gltf-validator.sh --out target/gltf-validator.jsonl
ADAPTIVE_PM_GLTF_VALIDATOR_REPORT=target/gltf-validator.jsonl \
    cargo test --locked --test library gltf_validator::the_loader_follows -- --ignored
bash scripts/ci-gltf-validator-generated.sh
cargo package --workspace --exclude adaptive-pm-downstream --locked --allow-dirty
bash scripts/ci-downstream.sh
if [ "$(id -u)" -eq 0 ]; then
    cargo build --release --locked
    bash scripts/ci-slurm.sh 4
else
    echo "test.sh: not root: the Slurm test (scripts/ci-slurm.sh) is skipped" >&2
fi
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    bash scripts/ci-fuzz.sh "${FUZZ_SECONDS:-60}"
else
    echo "test.sh: no nightly toolchain: the fuzzer (scripts/ci-fuzz.sh) is skipped" >&2
fi
echo "test.sh: all stages passed in $SECONDS s" >&2
