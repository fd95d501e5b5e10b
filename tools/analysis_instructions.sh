#!/usr/bin/env bash
# Instructions per directionality analysis, before and after a change, as a
# Markdown table (docs/reproduction.md, "Cost"). Valgrind counts
# instructions, which a shared machine's load does not move, unlike times.
#
#   tools/analysis_instructions.sh BEFORE AFTER
#
# BEFORE and AFTER are builds of `examples/analysis_one` (`cargo build
# --release --example analysis_one`, copied aside). One analysis is the
# count of 4 repetitions minus that of 1, over 3, so start-up is left out.
set -euo pipefail
shopt -s inherit_errexit
if [ $# -ne 2 ]; then
    echo "usage: $0 BEFORE AFTER (two builds of examples/analysis_one)" >&2
    exit 2
fi
for bin in "$1" "$2"; do
    if ! [ -x "$bin" ]; then
        echo "$0: $bin is not an executable build of examples/analysis_one" >&2
        exit 2
    fi
done
log=$(mktemp)
trap 'rm -f "$log"' EXIT
before=$(realpath "$1")
after=$(realpath "$2")
# Valgrind's instruction count of `BIN F REPS`; its log is shown if the
# count is missing (the binary failed, or valgrind did).
count() {
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$1" "$2" "$3" >"$log" 2>&1 || true
    local n
    n=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$log")
    if ! [[ $n =~ ^[0-9]+$ ]]; then
        echo "$0: no instruction count from $1 $2 $3:" >&2
        cat "$log" >&2
        exit 1
    fi
    echo "$n"
}
per_analysis() {
    local four one
    four=$(count "$1" "$2" 4)
    one=$(count "$1" "$2" 1)
    if ((four <= one)); then
        echo "$0: $1 did no more work for 4 analyses than for 1: not examples/analysis_one?" >&2
        exit 1
    fi
    echo $(((four - one) / 3))
}
echo "| function | before | after | ratio |"
echo "|---|---|---|---|"
for f in glass glass05 ct; do
    case $f in
    glass) name="rough glass alpha 0.09" ;;
    glass05) name="rough glass alpha 0.0025" ;;
    ct) name="Cook–Torrance 0.3" ;;
    esac
    b=$(per_analysis "$before" $f)
    a=$(per_analysis "$after" $f)
    awk -v n="$name" -v b="$b" -v a="$a" \
        'BEGIN { printf "| %s | %.2f M | %.2f M | %.3f |\n", n, b / 1e6, a / 1e6, a / b }'
done
