#!/usr/bin/env bash
# Prints a markdown table of the Cornell box's map checksums for every Embree
# kernel set this CPU runs, pinned, in classic and adaptive mode at
# N_MAX = 3e5, on 1 and 2 threads; and the same with glibc's FMA maths
# variants turned off (GLIBC_TUNABLES), which is how a host without FMA
# computes. Usage: tools/isa_checksums.sh [path/to/adaptive-pm]
set -euo pipefail
bin=${1:-target/release/adaptive-pm}
[ -x "$bin" ] || { echo "build it first: cargo build --release" >&2; exit 2; }
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
echo "CPU: $cpu; $(ldd --version | head -1); \`$0\`"
echo
echo "| kernels | glibc maths | mode | 1 thread | 2 threads |"
echo "|---|---|---|---|---|"
sum() { "$bin" trace cornell --mode "$1" --n-max 300000 --embree-isa "$2" --threads "$3" --json \
  | python3 -c 'import json,sys; print(json.load(sys.stdin)["checksum"])'; }
for isa in sse2 sse4.2 avx avx2 avx512; do
  "$bin" trace cornell --n-max 10 --embree-isa "$isa" --json >/dev/null 2>&1 || continue
  for math in fma sse2; do
    if [ "$math" = sse2 ]; then export GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4; else unset GLIBC_TUNABLES; fi
    for mode in classic adaptive; do
      echo "| $isa | $math | $mode | $(sum $mode $isa 1) | $(sum $mode $isa 2) |"
    done
  done
done
unset GLIBC_TUNABLES
