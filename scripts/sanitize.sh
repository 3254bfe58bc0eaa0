#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (docs/RELIABILITY.md).
# Builds with clang 14 into build-sanitize/ (-O1, assertions on, -fno-sanitize-recover=all: the
# first report stops the program, so a finding is a failed test), then runs CTest there.
# The same build carries libFuzzer's coverage instrumentation, so scripts/fuzz.sh reuses it.
# Usage: scripts/sanitize.sh [--ci] [ctest arguments, e.g. -R test_cli]
#   (whole suite) about 50 minutes on 2 cores from cold; run it before every submission that
#                 touches C++.
#   --ci          only the programs of the exact-arithmetic core (quadrature, B-splines,
#                 Bezier extraction, sparse rank modulo primes and over Q, T-meshes): the part
#                 that fits in every CI run (a few minutes, with ccache).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
sanitize_targets=()
if [[ "${1:-}" == "--ci" ]]; then
  shift
  sanitize_targets=(test_quadrature test_bspline test_spline_dimension test_tmesh_conformality)
  set -- -R '^test_(quadrature|bspline|spline_dimension|tmesh_conformality):' "$@"
fi
source "$root/scripts/sanitizers/build.sh"
ctest --test-dir "$build" --output-on-failure --no-tests=error -j "$(nproc)" "$@"
