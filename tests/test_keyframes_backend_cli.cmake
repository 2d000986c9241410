# ctest cli_keyframes_backend: hsi keyframes --backend (the Newton core of the drag's
# solves). An unknown name is refused (CLI11's exit code 105) naming the valid ones; cpu
# solves; cuda either solves on the device (when --backend auto picks CUDA) or, with no
# usable device or a build without CUDA, exits 1 with the reason auto gave, writing
# nothing, never a crash. hsi interpolate --backend cuda the same.
# -D: HSI_CLI, HSI_SCENE (a scene with handle targets), HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/scene_json.cmake)
set(W ${HSI_WORK_DIR})
small_scene(scene "${HSI_SCENE}" 2000)
file(WRITE ${W}/scene.json "${scene}")

run(105 ${HSI_CLI} keyframes ${W}/scene.json --force --backend gpu -o ${W}/gpu.json)
if(NOT RUN_OUTPUT MATCHES "--backend: gpu not in {auto,cpu,cuda}" OR EXISTS ${W}/gpu.json)
  message(FATAL_ERROR "hsi keyframes --backend gpu was not refused naming the backends, or wrote a scene")
endif()

run(0 ${HSI_CLI} keyframes ${W}/scene.json --force --backend cpu -o ${W}/cpu.json)
if(NOT RUN_OUTPUT MATCHES "Newton core: cpu\n" OR NOT RUN_OUTPUT MATCHES "reached all targets [^\n]*, certified" OR NOT EXISTS ${W}/cpu.json)
  message(FATAL_ERROR "hsi keyframes --backend cpu did not solve on the CPU core")
endif()

run(0 ${HSI_CLI} keyframes ${W}/scene.json --force --backend auto)
if(RUN_OUTPUT MATCHES "Newton core: cuda")
  set(have_cuda TRUE)
elseif(RUN_OUTPUT MATCHES "Newton core: cpu \\(--backend auto: CUDA not used: ([^\n]*)\\)\n")
  set(have_cuda FALSE)
  set(why "${CMAKE_MATCH_1}")
else()
  message(FATAL_ERROR "hsi keyframes --backend auto did not say which core it used and why")
endif()

if(have_cuda)
  run(0 ${HSI_CLI} keyframes ${W}/scene.json --force --backend cuda -o ${W}/cuda.json)
  if(NOT RUN_OUTPUT MATCHES "Newton core: cuda" OR NOT RUN_OUTPUT MATCHES "reached all targets [^\n]*, certified")
    message(FATAL_ERROR "hsi keyframes --backend cuda did not solve on the CUDA core")
  endif()
  message(STATUS "a CUDA device: --backend cuda solved")
else()
  run(1 ${HSI_CLI} keyframes ${W}/scene.json --force --backend cuda -o ${W}/cuda.json)
  string(FIND "${RUN_OUTPUT}" "hsi: error: --backend cuda: ${why}" at)
  if(at LESS 0 OR EXISTS ${W}/cuda.json)
    message(FATAL_ERROR "hsi keyframes --backend cuda without a device did not fail with the reason (${why}), or wrote a scene")
  endif()
  run(1 ${HSI_CLI} interpolate ${W}/cpu.json --frames 3 --backend cuda --png-frames 0 -o ${W}/frames)
  string(FIND "${RUN_OUTPUT}" "hsi: error: --backend cuda: ${why}" at)
  if(at LESS 0)
    message(FATAL_ERROR "hsi interpolate --backend cuda without a device did not fail with the reason (${why})")
  endif()
  message(STATUS "no CUDA device (${why}): --backend cuda refused with the reason")
endif()
