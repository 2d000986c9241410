#!/usr/bin/env bash
# Builds the libFuzzer harnesses (the `fuzz` preset: clang, ASan + UBSan, build-fuzz/)
# and runs each for N minutes on its seed corpus (tests/fuzz/corpus_*/ plus the
# bad-input corpus for scenes), keeping the grown corpus in build-fuzz/fuzz-corpus/.
# Writes a log per fuzzer and a summary (executions, exec/s, corpus size, findings)
# to build-fuzz/fuzz-logs/; crashing inputs land in build-fuzz/fuzz-artifacts/.
#   bash scripts/fuzz.sh [MINUTES=30] [fuzzer ...]     (default: all four)
# Exit status: non-zero when any fuzzer found a crash, leak, timeout or sanitizer report.
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-30}"
shift || true
fuzzers=("$@")
((${#fuzzers[@]})) || fuzzers=(fuzz_scene fuzz_png fuzz_frames fuzz_baked)
jobs="${HSI_FUZZ_BUILD_JOBS:-2}"
bash scripts/setup.sh
# clang and its libFuzzer runtime (Debian's clang, libclang-rt-dev) are needed here only.
if ! command -v clang++ >/dev/null || ! dpkg-query -W -f='${Status}' libclang-rt-dev 2>/dev/null | grep -q "install ok installed"; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends clang libclang-rt-dev
fi
[ -f build-fuzz/build.ninja ] || cmake --preset fuzz >/dev/null
cmake --build build-fuzz -j"$jobs" --target "${fuzzers[@]}"
mkdir -p build-fuzz/fuzz-logs build-fuzz/fuzz-artifacts
summary=build-fuzz/fuzz-logs/summary.txt
echo "hsi fuzzing $(date -u +%FT%TZ), ${minutes} min per fuzzer, commit $(git rev-parse --short HEAD 2>/dev/null || echo ?)" > "$summary"
status=0
for f in "${fuzzers[@]}"; do
  corpus=build-fuzz/fuzz-corpus/$f
  mkdir -p "$corpus"
  seeds=(tests/fuzz/corpus_$f)
  [ "$f" = fuzz_scene ] && seeds+=(tests/corpus/scenes)
  log=build-fuzz/fuzz-logs/$f.log
  echo "[fuzz] $f for $minutes min (log: $log)"
  set +e
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    build-fuzz/bin/$f -max_total_time=$((minutes * 60)) -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix=build-fuzz/fuzz-artifacts/$f- "$corpus" "${seeds[@]}" > "$log" 2>&1
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  speed=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  size=$(find "$corpus" -type f | wc -l)
  found=$(grep -cE '^==[0-9]+==ERROR|runtime error:|Test unit written to|deadly signal' "$log" || true)
  verdict="clean"
  if [ "$rc" != 0 ]; then verdict="FINDING (exit $rc; see $log and build-fuzz/fuzz-artifacts/)"; status=1; fi
  line=$(printf '%-12s %6s min  %12s execs  %8s exec/s  corpus %6s  reports %s  %s' "$f" "$minutes" "$execs" "$speed" "$size" "$found" "$verdict")
  echo "$line" | tee -a "$summary"
done
echo "[fuzz] summary in $summary"
exit $status
