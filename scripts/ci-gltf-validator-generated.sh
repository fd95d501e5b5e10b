#!/usr/bin/env bash
# The Khronos glTF-Validator over the glTF documents that the tests write at
# run time (tests/library/gltf_doc.rs: scenes with strips, textures,
# quantized or mirrored meshes, bad values), and the loader checked against
# its verdicts (tests/library/gltf_validator.rs, the generated files' rule).
# Needs what scripts/ci-gltf-validator.sh installs (run it first).
#
#   bash scripts/ci-gltf-validator-generated.sh
#
# The documents go to target/generated-gltf/ (named TEST-RANK.gltf), the
# report to target/gltf-validator-generated.jsonl.
set -euo pipefail
cd "$(dirname "$0")/.."

dir=target/generated-gltf
report=target/gltf-validator-generated.jsonl
rm -rf "$dir"
# Every library test that writes a document through gltf_doc::Doc.
ADAPTIVE_PM_GLTF_DUMP="$dir" cargo test --locked -q --test library gltf_ >/dev/null
mapfile -d '' -t files < <(find "$dir" -name '*.gltf' -print0 | sort -z)
if [ ${#files[@]} -eq 0 ]; then
  echo "ci-gltf-validator-generated: the tests wrote no glTF into $dir" >&2
  exit 1
fi
node tools/gltf-validator/validate.mjs --root . --out "$report" -- "${files[@]}"
echo "ci-gltf-validator-generated: ${#files[@]} files, report in $report" >&2
ADAPTIVE_PM_GLTF_VALIDATOR_GENERATED_REPORT="$report" \
    cargo test --locked --test library gltf_validator::generated_documents -- --ignored
