#!/usr/bin/env bash
# Builds and runs the tests: every CTest test except those labelled "slow" (the unit tests,
# `tb check --quick`, the layering rule, and the ASan+UBSan configuration, label "sanitize").
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
ctest --test-dir build -LE slow --output-on-failure -j"$(nproc)" "$@"
