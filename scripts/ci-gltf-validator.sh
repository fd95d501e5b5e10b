#!/usr/bin/env bash
# Runs the Khronos glTF-Validator (npm gltf-validator, pinned in
# tools/gltf-validator/package-lock.json) over every *.gltf and *.glb file
# tracked by git (issue 25). Each file is validated in its own node process,
# with a time limit and a heap cap; a deliberately invalid file (tests/hostile)
# does not fail the run. Installs nodejs and npm with apt-get when they are
# missing (idempotent and non-interactive, like scripts/setup.sh; needs root or sudo).
#
#   bash scripts/ci-gltf-validator.sh [--out FILE] [validate.mjs options...]
#
# Writes one JSON line per file to FILE (default target/gltf-validator.jsonl) and
# a table to stderr. Exits 0 unless the validator cannot run (1), or a file
# named by --require-valid PREFIX is not valid (3): see tools/gltf-validator/validate.mjs.
set -euo pipefail
cd "$(dirname "$0")/.."

PKGS=(nodejs npm)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ] && ! { command -v node >/dev/null && command -v npm >/dev/null; }; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "ci-gltf-validator: installing ${missing[*]}" >&2
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

(cd tools/gltf-validator && npm ci --no-audit --no-fund --loglevel=error >/dev/null)

out=target/gltf-validator.jsonl
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
mkdir -p "$(dirname "$out")"

mapfile -d '' -t files < <(git ls-files -z -- '*.gltf' '*.glb')
if [ ${#files[@]} -eq 0 ]; then
  echo "ci-gltf-validator: no *.gltf or *.glb file tracked" >&2
  : >"$out"
  exit 0
fi
node tools/gltf-validator/validate.mjs --root . --out "$out" "${args[@]}" -- "${files[@]}"
echo "ci-gltf-validator: ${#files[@]} files, report in $out" >&2
