#!/usr/bin/env bash
# Prints the crates a library user compiles with
#   adaptive-pm = { version = "...", default-features = false, features = ["embree"] }
# (normal and build dependencies, host target, adaptive-pm itself not counted)
# and fails when there are more than MAX_DEPS (default 40, issue #13).
# Also prints the count for a renderer's usual set (embree, gltf, image-io), with
# no feature, and with the default features (the command line) for comparison.
set -euo pipefail
cd "$(dirname "$0")/.."
MAX_DEPS="${MAX_DEPS:-40}"

deps() { # $@: feature flags
  cargo tree --locked -p adaptive-pm -e normal,build --prefix none "$@" \
    | sed -e 's/ (\*)$//' -e 's/ (proc-macro)$//' -e 's/ (\/.*)$//' \
    | grep -v '^adaptive-pm v' | sort -u
}

lib=$(deps --no-default-features --features embree)
renderer=$(deps --no-default-features --features embree,gltf,image-io)
full=$(deps)
nolib=$(deps --no-default-features)
n_lib=$(printf '%s\n' "$lib" | grep -c .)
n_full=$(printf '%s\n' "$full" | grep -c .)
n_renderer=$(printf '%s\n' "$renderer" | grep -c .)
n_none=$(printf '%s\n' "$nolib" | grep -c . || true)

echo "crates compiled for adaptive-pm, default-features = false, features = [\"embree\"]:"
printf '%s\n' "$lib" | sed 's/^/  /'
echo "dependencies: $n_lib with features [\"embree\"] (limit $MAX_DEPS), $n_renderer with [\"embree\", \"gltf\", \"image-io\"] (a renderer that loads glTF and writes images), $n_none with no feature, $n_full with the default features"
if [ "$n_lib" -gt "$MAX_DEPS" ]; then
  echo "count-deps: $n_lib crates with features [\"embree\"] is over the limit of $MAX_DEPS" >&2
  exit 1
fi
