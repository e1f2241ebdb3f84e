#!/usr/bin/env bash
# Installs the Debian packages the project builds with, when any is missing.
# Run as root (CI is root); with sudo otherwise.
set -euo pipefail
pkgs=(cmake g++ make pkg-config
      libglm-dev libtbb-dev libboost-dev libeigen3-dev libceres-dev
      nlohmann-json3-dev libfmt-dev libcli11-dev libembree-dev libopenexr-dev libtinyobjloader-dev
      libpng-dev libpugixml-dev libgtest-dev libgmock-dev libbenchmark-dev gnuplot-nox
      pybind11-dev python3-dev python3-numpy python3-pytest chromium libopenmpi-dev openmpi-bin)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends "${missing[@]}"
