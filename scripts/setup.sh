#!/usr/bin/env bash
# Installs the Debian 12 packages hsi needs (idempotent; skips what is present).
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev catch2 nlohmann-json3-dev libcli11-dev libstb-dev libpng-dev
  libfreetype-dev fonts-dejavu-core libcgal-dev libpolyclipping-dev libcairo2-dev
  python3 python3-numpy
  libvulkan-dev libvulkan-volk-dev glslang-tools spirv-tools mesa-vulkan-drivers vulkan-validationlayers
  libtinygltf-dev
  libglfw3-dev libimgui-dev xvfb xauth
  emscripten node-acorn chromium
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm (with node) for the Khronos glTF validator, unless a node install already has it.
command -v npm >/dev/null 2>&1 || missing+=(npm)
if ((${#missing[@]})); then
  echo "[setup] installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "[setup] all packages present"
fi

# The Khronos glTF validator (npm gltf-validator), project-local in .tools/: the glTF
# export tests run it on every file they write.
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -f "$root/.tools/node_modules/gltf-validator/package.json" ]; then
  echo "[setup] installing gltf-validator into .tools/"
  npm install --no-audit --no-fund --silent --prefix "$root/.tools" gltf-validator@2.0.0-dev.3.10
fi
# three.js for the web player (web/) and its browser test (ctest web_player), also in .tools/.
if [ ! -f "$root/.tools/node_modules/three/build/three.module.js" ]; then
  echo "[setup] installing three into .tools/"
  npm install --no-audit --no-fund --silent --prefix "$root/.tools" three@0.160.0
fi
