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
build="${KNOTWORK_SANITIZE_DIR:-$root/build-sanitize}"
targets=()
if [[ "${1:-}" == "--ci" ]]; then
  shift
  targets=(--target test_quadrature test_bspline)
  set -- -R '^test_(quadrature|bspline): ' "$@"
fi
"$root/scripts/install-deps.sh" --sanitize
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
if [[ ! -f "$build/build.ninja" ]]; then
  CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja \
    -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -g1" \
    -DKNOTWORK_SANITIZE=ON -DKNOTWORK_FUZZ=ON -DKNOTWORK_BUILD_BENCH=OFF
fi
# The build runs the test programs (Catch2 discovery lists their tests): the sanitizers'
# settings apply there too.
source "$root/scripts/sanitizers/environment.sh"
cmake --build "$build" --parallel "$(nproc)" "${targets[@]}"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)" "$@"
