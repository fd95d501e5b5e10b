#!/usr/bin/env bash
# Which glibc maths functions give other bits in their FMA and SSE2
# variants: builds tools/libm_variants.c and prints the functions whose
# hash over 20 million inputs differs (docs/determinism.md).
set -euo pipefail
cd "$(dirname "$0")"
bin=$(mktemp)
trap 'rm -f "$bin"' EXIT
cc -O1 -fno-builtin libm_variants.c -o "$bin" -lm
ldd --version | head -1
join <("$bin" | sort) <(GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4 "$bin" | sort) |
  awk '{ print $1, ($2 == $3 ? "same" : "differs") }'
