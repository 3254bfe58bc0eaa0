#!/usr/bin/env bash
# Installs and builds if needed, then runs the whole test suite with CTest.
# This is what CI runs (.ci/run).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
ctest --test-dir "${KNOTWORK_BUILD_DIR:-$root/build}" --output-on-failure -j "$(nproc)"
