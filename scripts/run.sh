#!/usr/bin/env bash
# The main job, headless: set up, build, interpolate a bundled scene and render it,
# writing the frames, a report, plots, frame drawings and rendered images (Vulkan;
# lavapipe without a GPU) to out/ (or the folder given as $1).
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
./build/bin/hsi render "$scene" "$out" -o "$out/render" --overlay boundary,handles
echo "[run] done: see $out/report.txt, $out/*.png, $out/frames/ and $out/render/ (frame_NNNN.png, contact_sheet.png)"
