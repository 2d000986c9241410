#!/usr/bin/env bash
# Builds hsi with AddressSanitizer and UndefinedBehaviorSanitizer (the `asan-ubsan`
# preset: build-asan/, RelWithDebInfo, CUDA off, warnings as errors) and runs the whole
# test suite under them (the preset's test environment: leak detection on, suppressions
# for third-party Vulkan/Mesa code only, in tests/sanitizers/). Any report fails.
# HSI_ASAN_JOBS sets build and test parallelism (default: all cores). Arguments go to
# ctest: .ci/run passes -LE long -E web_player (README, Robustness: Sanitizers).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
jobs="${HSI_ASAN_JOBS:-$(nproc)}"
cmake --preset asan-ubsan
cmake --build build-asan -j"$jobs"
export HSI_REQUIRE_GLTF_VALIDATOR=1
ctest --preset asan-ubsan -j"$jobs" "$@"
