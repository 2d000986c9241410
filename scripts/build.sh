#!/usr/bin/env bash
# Installs what is missing, then configures and builds hsi into build/ (Release).
# Extra CMake arguments are passed through, e.g. -DHSI_WARNINGS_AS_ERRORS=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j"$(nproc)"
