#!/usr/bin/env bash
# The sanitizer build shared by scripts/sanitize.sh and scripts/fuzz.sh: clang 14, ASan + UBSan
# with libFuzzer's coverage instrumentation, -O1 with assertions on, into build-sanitize/
# (KNOTWORK_SANITIZE_DIR). Installs what it needs, configures once, and builds the targets
# listed in the array `sanitize_targets` (all when it is empty). Sourced, so that the
# sanitizers' settings stay for what follows.
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${KNOTWORK_SANITIZE_DIR:-$root/build-sanitize}"
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
if [[ ${#sanitize_targets[@]} -gt 0 ]]; then
  cmake --build "$build" --parallel "$(nproc)" --target "${sanitize_targets[@]}"
else
  cmake --build "$build" --parallel "$(nproc)"
fi
