#!/usr/bin/env bash
# The main job, headless: set up, build, and interpolate a bundled scene, writing the
# frames, a report, plots and frame drawings to out/ (or the folder given as $1).
# HSI_SCENE and HSI_FRAMES choose another scene or frame count.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out}"
scene="${HSI_SCENE:-assets/bar_holes.json}"
frames="${HSI_FRAMES:-120}"
bash scripts/build.sh
mkdir -p "$out"
echo "[run] $scene: $frames frames -> $out/"
./build/bin/hsi info "$scene" --png "$out/cage.png" --json "$out/scene.json"
./build/bin/hsi interpolate "$scene" --frames "$frames" -o "$out"
echo "[run] done: see $out/report.txt, $out/*.png and $out/frames/"
