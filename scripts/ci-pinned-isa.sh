#!/usr/bin/env bash
# Runs the determinism tests (checksums across threads, batch sizes, casters
# and shards; the recorded pinned checksums; merge's refusals) once for every
# Embree kernel set this CPU runs, each pinned through ADAPTIVE_PM_EMBREE_ISA.
# A set the CPU lacks is named and skipped: Embree would crash on it.
set -euo pipefail
cd "$(dirname "$0")/.."
flags=$(grep -m1 '^flags' /proc/cpuinfo 2>/dev/null || true)
has() { for f in "$@"; do [[ " $flags " == *" $f "* ]] || return 1; done; }
declare -A needs=(
  [sse2]="sse2"
  [sse4.2]="sse4_2 popcnt"
  [avx]="sse4_2 popcnt avx"
  [avx2]="sse4_2 popcnt avx avx2 fma f16c bmi1 bmi2 abm"
  [avx512]="sse4_2 popcnt avx avx2 fma f16c bmi1 bmi2 abm avx512f avx512dq avx512cd avx512bw avx512vl"
)
ran=()
for isa in sse2 sse4.2 avx avx2 avx512; do
  # shellcheck disable=SC2086
  if ! has ${needs[$isa]}; then
    echo "ci-pinned-isa: this CPU cannot run Embree's $isa kernels: skipped" >&2
    continue
  fi
  echo "ci-pinned-isa: determinism tests with Embree's $isa kernels pinned" >&2
  ADAPTIVE_PM_EMBREE_ISA=$isa cargo test --locked -q --test library --test command -- \
    checksum shards:: shards_cli:: isa_pinning:: isa_cli:: raycast:: embree_wrapper::
  ran+=("$isa")
done
echo "ci-pinned-isa: passed with ${ran[*]} pinned" >&2
