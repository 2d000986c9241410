# ctest web_player: the web player (web/) in headless Chromium against hsi render.
# Interpolates a bundled scene, bakes the frames (hsi bake --from), renders three of
# them with hsi render, stages the player (build/web: hsib.js/.wasm, player.*, the
# GLSL) with three.js, the .hsib and the texture, and runs web/web_player_check.py
# (HTTP server, Chromium screenshots, comparison; its tolerance is stated there),
# then again with the distortion colouring.
# Skips when emcc, chromium, python3 or three.js is missing, unless HSI_REQUIRE_WEB=1.
# -D: HSI_CLI, HSI_SCENE, HSI_WEB_DIR, HSI_THREE, HSI_CHROMIUM, HSI_PYTHON, HSI_EMCC, HSI_COMPARE, HSI_WORK_DIR
cmake_minimum_required(VERSION 3.20)
set(missing "")
if(NOT HSI_EMCC OR NOT EXISTS ${HSI_WEB_DIR}/hsib.js)
  list(APPEND missing "emscripten (emcc; the player in build/web)")
endif()
if(NOT HSI_CHROMIUM)
  list(APPEND missing "chromium")
endif()
if(NOT HSI_PYTHON)
  list(APPEND missing "python3")
endif()
if(NOT EXISTS ${HSI_THREE})
  list(APPEND missing "three.js (${HSI_THREE})")
endif()
if(missing)
  list(JOIN missing ", " m)
  if("$ENV{HSI_REQUIRE_WEB}" AND NOT "$ENV{HSI_REQUIRE_WEB}" STREQUAL "0")
    message(FATAL_ERROR "HSI_REQUIRE_WEB is set but the web test's tools are missing: ${m} (scripts/setup.sh installs them)")
  endif()
  message("SKIPPED: missing ${m} (scripts/setup.sh installs them)")
  return()
endif()
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR}/site)
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ARGN}:\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()
set(W 320)
set(H 240)
run(${HSI_CLI} interpolate ${HSI_SCENE} --frames 5 --samples 1000 -o ${HSI_WORK_DIR}/interp)
run(${HSI_CLI} bake ${HSI_SCENE} --from ${HSI_WORK_DIR}/interp --mesh-vertices 2000 -o ${HSI_WORK_DIR}/site/seq.hsib)
run(${HSI_CLI} render ${HSI_SCENE} ${HSI_WORK_DIR}/interp --frames 0,2,4 --size ${W}x${H} --overlay none --no-labels
    --background white --no-contact-sheet --mesh-vertices 2000 -o ${HSI_WORK_DIR}/render)
file(GLOB staged ${HSI_WEB_DIR}/*)
file(COPY ${staged} ${HSI_THREE} DESTINATION ${HSI_WORK_DIR}/site)
# The scene's texture (its "texture" key, next to the scene file).
file(READ ${HSI_SCENE} scene_json)
string(JSON texture GET "${scene_json}" texture)
get_filename_component(scene_dir ${HSI_SCENE} DIRECTORY)
file(COPY_FILE ${scene_dir}/${texture} ${HSI_WORK_DIR}/site/texture.png)
run(${HSI_PYTHON} ${HSI_COMPARE} ${HSI_CHROMIUM} ${HSI_WORK_DIR}/site ${HSI_WORK_DIR}/render ${W} ${H} 0 2 4)
# The distortion colouring (&distortion=LO,HI: derivative rows, hsib_singular_values in WebGL2).
run(${HSI_PYTHON} ${HSI_COMPARE} ${HSI_CHROMIUM} ${HSI_WORK_DIR}/site ${HSI_WORK_DIR}/render ${W} ${H} --distortion 1,1.5 0 2 4)
