#!/usr/bin/env bash
# Runs every seeded statistical test of the library suite with N seeds
# (default 32) and prints a table: test, failures out of N, the worst
# deviation in sigmas and the narrowest bound in sigmas.
#
#   scripts/seed-sweep.sh [N] [--out FILE.md]
#
# Each seeded test mixes ADAPTIVE_PM_TEST_SEED into its own seed
# (tests/common/mod.rs, `seed`), and reports each check as a `seed-sweep:`
# line (`assert_within_noise`) to the file ADAPTIVE_PM_SWEEP_LOG names.
# Seed 1 runs the whole library suite to find those tests; seeds 2..N run
# only them. ADAPTIVE_PM_EMBREE_ISA, if set,
# pins Embree's kernel set for every run. Exits 1 when any run failed.
set -euo pipefail
cd "$(dirname "$0")/.."
n=32
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    *) n="$1"; shift ;;
  esac
done
case "$n" in ''|*[!0-9]*|0) echo "seed-sweep: N must be a positive integer, not '$n'" >&2; exit 2 ;; esac
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
cargo test --locked --test library --no-run -q 2>/dev/null || cargo test --locked --test library --no-run
run() { # seed, filters...
  local k=$1; shift
  ADAPTIVE_PM_TEST_SEED=$k ADAPTIVE_PM_SWEEP_LOG="$logs/$k.sweep" cargo test --locked -q --test library -- --nocapture "$@" >"$logs/$k.log" 2>&1 || true
}
start=$(date +%s)
echo "seed-sweep: seed 1/$n (the whole library suite)" >&2
run 1
touch "$logs/1.sweep"
mapfile -t tests < <(sed -n 's/^seed-sweep: test=\([^ ]*\) .*/\1/p' "$logs/1.sweep" | sort -u)
if [ ${#tests[@]} -eq 0 ]; then
  echo "seed-sweep: no test printed a seed-sweep line" >&2
  cat "$logs/1.log" >&2
  exit 1
fi
for k in $(seq 2 "$n"); do
  echo "seed-sweep: seed $k/$n (${#tests[@]} tests, $(( $(date +%s) - start )) s so far)" >&2
  run "$k" --exact "${tests[@]}"
done
args=(--seeds "$n" --isa "${ADAPTIVE_PM_EMBREE_ISA:-native}")
[ -n "$out" ] && args+=(--out "$out")
python3 tools/seed_sweep_table.py "${args[@]}" "$logs"/*.log
