# ctest cli_overlap (issue #20): a scene whose second keyframe rolls a bar over itself
# (tests/scenes/bent_bar.json: certified locally injective, not globally injective; its
# first keyframe rolls the bar less than a turn and does not overlap).
# hsi keyframes and hsi interpolate warn that it overlaps itself, report.txt/report.json
# say so, the frames file carries flag 8 and, with Vulkan, hsi render labels the frame
# "OVERLAPS ITSELF" and counts it (the contact sheet's title too).
# -D: HSI_CLI, HSI_SCENE, HSI_WORK_DIR, HSI_WITH_RENDER
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)

run(0 ${HSI_CLI} keyframes ${HSI_SCENE} -o ${HSI_WORK_DIR}/solved.json)
if(NOT RUN_OUTPUT MATCHES "WARNING: keyframe 1 \\(t = [0-9.]+\\) overlaps itself: the image of the outer loop edge")
  message(FATAL_ERROR "hsi keyframes did not warn that keyframe 1 overlaps itself")
endif()
if(RUN_OUTPUT MATCHES "keyframe 0 \\(t = [0-9.]+\\) overlaps itself")
  message(FATAL_ERROR "hsi keyframes warned about the identity keyframe")
endif()

set(frames ${HSI_WORK_DIR}/frames)
run(0 ${HSI_CLI} interpolate ${HSI_SCENE} --frames 3 --png-frames 3 -o ${frames})
foreach(want "WARNING: keyframe 1 overlaps itself" "WARNING: [12] frame\\(s\\) overlap themselves"
        "certified locally injective")
  if(NOT RUN_OUTPUT MATCHES "${want}")
    message(FATAL_ERROR "hsi interpolate did not print '${want}'")
  endif()
endforeach()
file(READ ${frames}/report.txt txt)
if(NOT txt MATCHES "overlap themselves" OR NOT txt MATCHES "YES")
  message(FATAL_ERROR "report.txt does not flag the overlapping frame")
endif()
file(READ ${frames}/report.json json)
string(JSON last GET "${json}" frames 2 overlaps)
string(JSON first GET "${json}" frames 0 overlaps)
if(NOT last STREQUAL "ON" OR NOT first STREQUAL "OFF")
  message(FATAL_ERROR "report.json: frames 0 and 2 overlaps = ${first}, ${last} (expected false, true)")
endif()
if(NOT EXISTS ${frames}/frames/frame_0002.png)
  message(FATAL_ERROR "hsi interpolate did not draw frame 2")
endif()

if(HSI_WITH_RENDER)
  run(0 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/render --size 240 --no-texture --validation)
  if(NOT RUN_OUTPUT MATCHES "[12] of the rendered frames OVERLAP ITSELF")
    message(FATAL_ERROR "hsi render did not count the overlapping frames")
  endif()
  foreach(f frame_0002.png contact_sheet.png)
    if(NOT EXISTS ${HSI_WORK_DIR}/render/${f})
      message(FATAL_ERROR "hsi render did not write ${f}")
    endif()
  endforeach()
endif()
