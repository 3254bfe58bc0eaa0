#!/usr/bin/env bash
# Coverage-guided fuzzing of every input format with libFuzzer (docs/RELIABILITY.md).
# Builds the harnesses of fuzz/ in the sanitizer build (build-sanitize/, clang, ASan + UBSan),
# seeds each corpus from the shipped inputs (cases/ and tests/bad_inputs/), and runs every
# harness for a fixed time. A crash, a sanitizer report, a time-out (> 10 s on one input) or
# more than 2 GB of memory stops that harness and leaves the input as fuzz/findings/<harness>/;
# turn each into a regression test in tests/bad_inputs/ once fixed.
# Usage: scripts/fuzz.sh [SECONDS per harness, default 600] [HARNESS ...]
#   Corpora grow in build-sanitize/fuzz-corpus/<harness>/ (not in git) and are reused.
#   KNOTWORK_FUZZ_JOBS=N runs N harnesses at a time (default: the number of cores).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-600}"
shift || true
all=(fuzz_case_toml fuzz_case_json fuzz_case_xml fuzz_geometry_txt fuzz_tmesh fuzz_collection fuzz_quad_mesh fuzz_gluing fuzz_expression)
harnesses=("$@")
if [[ $# -eq 0 ]]; then harnesses=("${all[@]}"); fi

sanitize_targets=("${harnesses[@]}")
source "$root/scripts/sanitizers/build.sh"
# libFuzzer checks leaks itself (-detect_leaks); CLN's start-up allocation is suppressed as in the tests.

seed() {  # seed HARNESS DIR: the shipped inputs of that format
  local dir="$2"
  mkdir -p "$dir"
  case "$1" in
    fuzz_case_toml) cp "$root"/cases/*.toml "$root"/tests/bad_inputs/*.toml "$dir"/ ;;
    fuzz_case_json) cp "$root"/tests/bad_inputs/case_json_*.json "$dir"/
                    for f in "$root"/cases/square_sinsin.toml "$root"/cases/lshape_adaptive_pt.toml "$root"/cases/g1_three_quads.toml; do
                      /usr/bin/python3 -c 'import json,sys,tomllib; print(json.dumps(tomllib.load(open(sys.argv[1],"rb"))))' "$f" \
                        > "$dir/$(basename "$f" .toml).json"
                    done ;;
    fuzz_case_xml) cp "$root"/cases/*.xml "$root"/cases/geometries/*.xml "$root"/tests/bad_inputs/*.xml "$dir"/ ;;
    fuzz_geometry_txt) cp "$root"/cases/geometries/*.txt "$root"/tests/bad_inputs/*.txt "$dir"/ ;;
    fuzz_tmesh) cp "$root"/cases/tmeshes/*.toml "$root"/tests/bad_inputs/tmesh_*.toml "$dir"/ ;;
    fuzz_collection) cp "$root"/cases/collections/*.json "$root"/tests/bad_inputs/collection_*.json "$dir"/ ;;
    fuzz_quad_mesh) cp "$root"/cases/meshes/*.obj "$root"/tests/bad_inputs/*.obj "$dir"/ ;;
    fuzz_gluing) cp "$root"/cases/meshes/*.json "$root"/tests/bad_inputs/gluing_*.json "$dir"/ ;;
    fuzz_expression) i=0
      grep -ho '"[^"]*"' "$root"/cases/*.toml | tr -d '"' | grep -E '[xyz]' | sort -u | while read -r e; do
        i=$((i + 1)); printf '%s' "$e" > "$dir/expr_$i"; done ;;
  esac
}

status=0
run_one() {
  local h="$1" corpus="$build/fuzz-corpus/$1" findings="$root/fuzz/findings/$1" log="$build/fuzz-logs/$1.log"
  mkdir -p "$findings" "$(dirname "$log")"
  [[ -d "$corpus" ]] || seed "$h" "$corpus"
  local max_len=8192
  [[ "$h" == fuzz_expression ]] && max_len=512
  if "$build/fuzz/$h" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="$max_len" \
       -artifact_prefix="$findings/" -print_final_stats=1 > "$log" 2>&1; then
    echo "fuzz: $h: no crash in ${seconds} s ($(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$') runs," \
         "$(grep -o 'cov: [0-9]*' "$log" | tail -1), corpus $(ls "$corpus" | wc -l) inputs)"
  else
    echo "fuzz: $h: FOUND a failure: $(ls -t "$findings" | head -1) (log: $log)"
    return 1
  fi
}
jobs_at_once="${KNOTWORK_FUZZ_JOBS:-$(nproc)}"
running=0
for h in "${harnesses[@]}"; do
  if (( running >= jobs_at_once )); then
    wait -n || status=1
    running=$((running - 1))
  fi
  run_one "$h" &
  running=$((running + 1))
done
while (( running > 0 )); do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
