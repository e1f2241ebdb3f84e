#!/usr/bin/env bash
# Configures and builds (Release, warnings as errors) into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTB_WERROR=ON
cmake --build build -j"$(nproc)"
