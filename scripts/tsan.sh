#!/usr/bin/env bash
# ThreadSanitizer over the threaded parts of the pipeline (docs/RELIABILITY.md): builds the
# `knotwork` command with clang 14 and -fsanitize=thread into build-tsan/, then runs cases whose
# assembly, error norms, estimator and sampling run on 2 OpenMP threads. LLVM's Archer tool
# (OMP_TOOL_LIBRARIES) tells TSan about OpenMP's own synchronisation, which it cannot see in the
# uninstrumented runtime; without it every parallel region reports false races.
# Usage: scripts/tsan.sh        (one run; about 30 minutes on 2 cores from cold)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${KNOTWORK_TSAN_DIR:-$root/build-tsan}"
"$root/scripts/install-deps.sh" --sanitize
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
if [[ ! -f "$build/build.ninja" ]]; then
  CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja \
    -DCMAKE_BUILD_TYPE=Tsan -DCMAKE_CXX_FLAGS_TSAN="-O1 -g1" -DKNOTWORK_SANITIZE_THREAD=ON \
    -DKNOTWORK_BUILD_TESTS=OFF -DKNOTWORK_BUILD_PYTHON=OFF -DKNOTWORK_BUILD_BENCH=OFF
fi
cmake --build "$build" --parallel "$(nproc)" --target knotwork
export OMP_NUM_THREADS=2 OMP_TOOL_LIBRARIES=/usr/lib/llvm-14/lib/libarcher.so  # libomp-14-dev
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/sanitizers/tsan.supp${TSAN_OPTIONS:+:$TSAN_OPTIONS}"
# VTK runs its own loops on TBB threads that TSan cannot see synchronise (reports inside
# vtkCommonDataModel, allocated on a TBB worker, freed on the main thread): VTK's threading is
# not under test here, so it runs sequentially.
export VTK_SMP_BACKEND_IN_USE=Sequential
[[ -f "$OMP_TOOL_LIBRARIES" ]] || { echo "tsan: Archer (libarcher.so) not found; install libomp-14-dev" >&2; exit 1; }
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
status=0
for args in "run cases/square_sinsin.toml --elements 64 --solver direct" \
            "run cases/quarter_annulus.toml --elements 32 --solver iterative" \
            "converge cases/lshape_knot_segments.toml --levels 2" \
            "adapt cases/lshape_adaptive_pt.toml --steps 3" \
            "adapt cases/lshape_adaptive_thb.toml --steps 12" \
            "adapt cases/lshape_adaptive_lr.toml --steps 8" \
            "run cases/g1_three_quads.toml" \
            "run cases/g1_mixed_valences.toml" \
            "run cases/g1_sphere_xy.toml" \
            "run cases/g1_sphere_dodecahedron.toml"; do
  if (cd "$root" && "$build/app/knotwork" $args --out "$out/$(echo "$args" | tr ' /' '__')" -q > /dev/null); then
    echo "tsan: ok   knotwork $args"
  else
    echo "tsan: FAIL knotwork $args"
    status=1
  fi
done
exit $status
