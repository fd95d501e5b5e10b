#!/bin/bash
# Alternates two builds of examples/trace_vs_raw, one round each in turn, so
# that machine drift hits both alike; prints one line a run: the build (A or
# B), its "of raw", tracer ns a ray and added ns a ray.
# usage: tools/ab_trace_vs_raw.sh A_BINARY B_BINARY ROUNDS [trace_vs_raw args: N_MAX THREADS 1]
A=$1; B=$2; R=$3; shift 3
for i in $(seq 1 "$R"); do
  for X in A B; do
    bin=${!X}
    out=$("$bin" "$@" 2>&1 | awk '$1 ~ /^[0-9]+$/ && NF==8 {print $5, $7, $8}' | tail -1)
    echo "$X $out"
  done
done
