#!/usr/bin/env bash
# Main job: install what is needed, build, and run `tb check` on the built-in quick suite.
# Writes reports/out/latest/index.html and results.json; exits non-zero when a check fails.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/tb check --quick --out reports/out/latest "$@"
