#!/usr/bin/env bash
# Writes assets/fonts/DejaVuSans.ttf, the font the plots draw with (compiled in
# by src/experiments/plot.rs with the `experiments` feature): DejaVu Sans from
# Debian's fonts-dejavu-core, cut to the characters a plot label may use
# (Basic Latin, Latin-1, Greek, punctuation, super- and subscripts, arrows,
# mathematical operators) and without hinting (ab_glyph does not read it):
# 77 KB instead of 760 KB in the crate and the binary.
# Needs fonttools (`pip install fonttools`) and fonts-dejavu-core.
set -euo pipefail
cd "$(dirname "$0")/.."
SRC="${1:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}"
pyftsubset "$SRC" \
  --unicodes="U+0020-007E,U+00A0-00FF,U+0370-03FF,U+2010-205E,U+2070-209F,U+2190-21FF,U+2200-22FF" \
  --layout-features='kern,liga' --no-hinting --desubroutinize \
  --output-file=assets/fonts/DejaVuSans.ttf
ls -l assets/fonts/DejaVuSans.ttf
