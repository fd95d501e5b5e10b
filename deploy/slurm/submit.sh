#!/bin/bash
# Submits a sharded trace: an array of N trace tasks, then the merge once all
# succeeded. Usage: submit.sh N [sbatch options for both jobs...]
# Environment: APM_BIN, APM_SCENE, APM_ARGS, APM_DIR (see trace-array.sbatch).
# Prints the merge job's id.
set -euo pipefail
n=${1:?usage: submit.sh N [sbatch options]}
shift
here=$(cd "$(dirname "$0")" && pwd)
jid=$(sbatch --parsable --array="0-$((n - 1))" "$@" "$here/trace-array.sbatch")
sbatch --parsable --dependency="afterok:${jid%%;*}" --kill-on-invalid-dep=yes "$@" \
    "$here/merge.sbatch"
