#!/usr/bin/env bash
# Installs every Debian 12 package isocharts needs to build, test and run.
# Idempotent and non-interactive: packages already present are skipped, and
# `apt-get update` runs at most once per invocation (only when something is missing).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache git
  libcgal-dev libgmp-dev libmpfr-dev
  libeigen3-dev libspectra-dev
  libopenimageio-dev openimageio-tools libopenexr-dev
  libflann-dev liblz4-dev
  catch2 libtbb-dev libcli11-dev
  libspdlog-dev libfmt-dev nlohmann-json3-dev libtinygltf-dev
  libboost-dev libboost-graph-dev
  python3
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null 2>&1 || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
