#!/usr/bin/env bash
# Set up, build (warnings as errors) and run the whole test suite through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh -DHSI_WARNINGS_AS_ERRORS=ON
# lavapipe is installed by setup.sh: Vulkan tests must run, not skip.
export HSI_REQUIRE_VULKAN=1
# setup.sh installs the Khronos glTF validator: glTF exports must be validated, not skipped.
export HSI_REQUIRE_GLTF_VALIDATOR=1
# setup.sh installs Xvfb: the viewer test (hsi-viewer under xvfb-run) must run, not skip.
export HSI_REQUIRE_VIEWER=1
# setup.sh installs emscripten, chromium and three.js: the web player test must run, not skip.
export HSI_REQUIRE_WEB=1
cd build
ctest --output-on-failure -j"$(nproc)" --timeout 900
