#!/usr/bin/env bash
# The main job, headless: set up, build, and run hsi on a bundled scene, writing
# images and a report to out/ (or the folder given as the first argument).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out}"
scene="${HSI_SCENE:-assets/bar_holes.json}"
bash scripts/build.sh
mkdir -p "$out"
echo "[run] scene $scene -> $out/"
./build/bin/hsi info "$scene" --png "$out/cage.png" --json "$out/report.json"
echo "[run] wrote $out/cage.png (shape, cage, hole points, samples) and $out/report.json"
