#!/usr/bin/env bash
# Runs the scene-loading fuzz target (fuzz/, issue 12) for a bounded time.
#   scripts/ci-fuzz.sh [SECONDS]   (default 60)
# Needs the nightly toolchain; installs cargo-fuzz when missing. The corpus
# starts from assets/ and tests/hostile/ (the regression files); a crash
# leaves its input under fuzz/artifacts/scene_load/ and fails the script:
# keep it under tests/hostile/ (named fuzz-*) so `cargo test` replays it.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-60}"
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    cargo +nightly install cargo-fuzz --locked
fi
CORPUS=fuzz/corpus/scene_load
mkdir -p "$CORPUS"
cp -n assets/*.gltf tests/hostile/*.gltf tests/gltf/*.gltf "$CORPUS"/ 2>/dev/null || true
# The documents the tests write (kept by scripts/ci-gltf-validator-generated.sh,
# which scripts/test.sh runs first): one seed per feature the tests exercise.
cp -n target/generated-gltf/*.gltf "$CORPUS"/ 2>/dev/null || true
# Binary seeds for the compressed-buffer decoders (under -max_len).
cp -n assets/blender_scene_meshopt*.glb assets/blender_layers.glb "$CORPUS"/ 2>/dev/null || true
for f in tests/hostile/fuzz-* tests/hostile/crash-*; do
    [ -e "$f" ] && cp -n "$f" "$CORPUS"/
done
# -rss_limit_mb: loading must stay bounded; -timeout: no input may hang.
cargo +nightly fuzz run scene_load "$CORPUS" -- \
    -max_total_time="$SECONDS_TO_RUN" -rss_limit_mb=2048 -timeout=10 -max_len=65536 \
    -dict=fuzz/gltf.dict -print_final_stats=1
