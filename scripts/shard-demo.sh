#!/bin/bash
# The README's sharding figures: a run whose map exceeds one process's memory
# budget fails or is bound as one process, and succeeds as N shards (one after
# the other here; a scheduler runs them in parallel), merging to the checksum
# of the same run traced without a budget. Prints a markdown table.
# Usage: scripts/shard-demo.sh [SCENE] [N_MAX] [SHARDS] [BUDGET_MB]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-cornell} nmax=${2:-2000000} n=${3:-16} mb=${4:-160}
bin=${APM_BIN:-target/release/adaptive-pm}
dir=$(mktemp -d /tmp/shard-demo.XXXXXX)
trap 'rm -rf "$dir"' EXIT
args=(--mode adaptive --n-max "$nmax" --seed 1)
field() { python3 -c "import json,sys; v=json.loads(sys.stdin.read()); print(v[sys.argv[1]])" "$1"; }
now() { date +%s.%N; }
since() { printf "%.2f" "$(echo "$(now) - $1" | bc)"; }

echo "| run | result | photons | wall time (s) | checksum |"
echo "|---|---|---|---|---|"
t=$(now)
whole=$("$bin" trace "$scene" "${args[@]}" --json)
echo "| one process, no budget | ok | $(field stored <<<"$whole") | $(since "$t") | $(field checksum <<<"$whole") |"
t=$(now)
if one=$("$bin" trace "$scene" "${args[@]}" --budget-mb "$mb" --json 2>"$dir/err"); then
    echo "| one process, --budget-mb $mb | budget bound: $(field budget_bound <<<"$one") | $(field stored <<<"$one") | $(since "$t") | $(field checksum <<<"$one") |"
else
    echo "| one process, --budget-mb $mb | refused: $(sed 's/|/\\|/g' "$dir/err" | cut -c1-90)... | - | $(since "$t") | - |"
fi
total=0
max=0
for i in $(seq 0 $((n - 1))); do
    t=$(now)
    s=$("$bin" trace "$scene" "${args[@]}" --budget-mb "$mb" --shard "$i/$n" --out "$dir/s$i.apm" --json)
    dt=$(since "$t")
    [ "$(field budget_bound <<<"$s")" = "False" ] || { echo "shard $i was budget bound" >&2; exit 1; }
    total=$(echo "$total + $dt" | bc)
    max=$(echo "if ($dt > $max) $dt else $max" | bc)
done
echo "| $n shards, --budget-mb $mb each | ok | (per shard) | sum $total, slowest $max | |"
t=$(now)
m=$("$bin" merge "$dir"/s*.apm --out "$dir/map.apm" --json)
echo "| merge of the $n shards | ok | $(field photons <<<"$m") | $(since "$t") | $(field checksum <<<"$m") |"
echo
echo "Merged map file: $(stat -c %s "$dir/map.apm") bytes. Same checksum as the unbounded run: $([ "$(field checksum <<<"$m")" = "$(field checksum <<<"$whole")" ] && echo yes || echo NO)."
