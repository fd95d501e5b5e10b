#!/bin/bash
# usage: ab.sh A B ROUNDS ARGS...  -> alternates, prints ratio lines
A=$1; B=$2; R=$3; shift 3
for i in $(seq 1 $R); do
  for X in A B; do
    bin=${!X}
    out=$($bin "$@" 2>&1 | awk '$1 ~ /^[0-9]+$/ && NF==8 {print $5, $7, $8}' | tail -1)
    echo "$X $out"
  done
done
