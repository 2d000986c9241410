#!/usr/bin/env bash
# Runs the CUDA test cases under NVIDIA's compute-sanitizer, for the GPU machine (the
# suite's [cuda] cases skip without a GPU, and so does this script):
#   memcheck  over every [cuda] case: out-of-bounds, misaligned and leaked device memory;
#   synccheck over the [cuda][dense] cases: barriers and warp syncs used correctly.
# Any error a tool reports, or a failed test under it, fails the script (exit 1), with
# the tool's first reports and its summary printed. Logs go to $HSI_SANITIZER_LOGS
# (default <build>/cuda-sanitizer-logs).
#
# Usage: scripts/cuda_sanitizers.sh [build dir] [tool[=Catch2 filter] ...]
#   tools: memcheck, synccheck (the default: both, with the filters above) and racecheck
#   (over [cuda][dense] unless given a filter). racecheck is not a pass/fail check for
#   this code: it models barriers, not the release/acquire flags through which the
#   dense solves' warps and cluster blocks hand values over (dense_cholesky.cu), so it
#   reports every such hand-off as a hazard (README, Speed: 2026-12-06).
#   HSI_SANITIZER_TIMEOUT=S stops each tool after S seconds (a failure: what it had not
#   run is not checked).
# The build needs CUDA (cmake finds nvcc); its device code carries -lineinfo, so reports
# name file:line.
set -uo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
shift || true
tools=("$@")
[ ${#tools[@]} -eq 0 ] && tools=(memcheck synccheck)
tests="$build/tests/hsi_tests"
logs="${HSI_SANITIZER_LOGS:-$build/cuda-sanitizer-logs}"

sanitizer="$(command -v compute-sanitizer || true)"
for d in /usr/local/cuda/bin /usr/local/cuda-13.0/bin; do
  [ -z "$sanitizer" ] && [ -x "$d/compute-sanitizer" ] && sanitizer="$d/compute-sanitizer"
done
if [ -z "$sanitizer" ]; then
  echo "cuda_sanitizers: compute-sanitizer not found (CUDA toolkit's bin/): skipped"
  exit 0
fi
if [ ! -x "$tests" ]; then
  echo "cuda_sanitizers: $tests not built" >&2
  exit 2
fi
if ! nvidia-smi -L >/dev/null 2>&1; then
  echo "cuda_sanitizers: no NVIDIA GPU here: skipped"
  exit 0
fi
mkdir -p "$logs"

status=0
printf '%-10s %-22s %8s %8s  %s\n' tool cases seconds errors result
limit=()
[ -n "${HSI_SANITIZER_TIMEOUT:-}" ] && limit=(timeout "$HSI_SANITIZER_TIMEOUT")
for spec in "${tools[@]}"; do
  tool="${spec%%=*}"
  case "$tool" in
    memcheck) filter="[cuda]"; extra=(--leak-check full) ;;
    synccheck) filter="[cuda][dense]"; extra=() ;;
    racecheck) filter="[cuda][dense]"; extra=(--racecheck-report all) ;;
    *) echo "cuda_sanitizers: unknown tool '$tool' (memcheck, synccheck, racecheck)" >&2; exit 2 ;;
  esac
  [ "$spec" != "$tool" ] && filter="${spec#*=}"
  log="$logs/$tool.log"
  start=$(date +%s)
  "${limit[@]}" "$sanitizer" --tool "$tool" "${extra[@]}" --error-exitcode 90 --print-limit 200 \
    "$tests" "$filter" >"$log" 2>&1
  rc=$?
  secs=$(( $(date +%s) - start ))
  errors="$(grep -Eo 'ERROR SUMMARY: [0-9]+' "$log" | tail -1 | grep -Eo '[0-9]+' || true)"
  [ -z "$errors" ] && errors="?"
  result=passed
  if [ "$rc" -ne 0 ] || [ "$errors" != "0" ]; then
    result="FAILED (exit $rc)"
    status=1
  fi
  printf '%-10s %-22s %8s %8s  %s\n' "$tool" "$filter" "$secs" "$errors" "$result"
  if [ "$result" != passed ]; then
    grep -E '^========= (Error|Invalid|Race|Warning|Barrier|    at )' "$log" | head -40 | sed 's/^/    /'
    tail -5 "$log" | sed 's/^/    /'
  fi
done
echo "logs: $logs"
exit "$status"
