#!/usr/bin/env bash
# Installs what adaptive-pm needs on a fresh Debian or Ubuntu machine:
# Embree (3 or 4, whichever the distribution ships), libclang for bindgen, a C compiler,
# python3 (the MSRV check and the Slurm test read JSON with it).
# Idempotent and non-interactive; needs root or sudo for apt-get.
set -euo pipefail
PKGS=(libembree-dev libclang-dev clang pkg-config build-essential python3)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing ${missing[*]}" >&2
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust (https://rustup.rs) first" >&2; exit 1; }
