# ctest cli_reversed_loops (issue #20): a bundled scene whose every loop is listed the
# other way round is the same scene. hsi keyframes --force (every keyframe solved again
# from its handle targets) writes the same file byte for byte, and hsi interpolate makes
# the same frames from the file's keyframes: loading turns each loop to the normal
# orientation (outer counter-clockwise, holes clockwise), so nothing after it may see the
# orientation the file gave. |G| = 2000 to keep it quick.
# -D: HSI_CLI, HSI_SCENE (a scene with handle targets and keyframe coefficients), HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/scene_json.cmake)
set(W ${HSI_WORK_DIR})

small_scene(given "${HSI_SCENE}" 2000)
reverse_shape_loops(reversed "${given}")
file(WRITE ${W}/given.json "${given}")
file(WRITE ${W}/reversed.json "${reversed}")
# The reversed file really lists the loops the other way round.
string(JSON first_given GET "${given}" shape outer 0)
string(JSON first_reversed GET "${reversed}" shape outer 0)
string(JSON n LENGTH "${given}" shape outer)
math(EXPR last "${n} - 1")
string(JSON last_given GET "${given}" shape outer ${last})
if(first_given STREQUAL first_reversed OR NOT first_reversed STREQUAL last_given)
  message(FATAL_ERROR "the reversed scene's outer loop is not the given one reversed")
endif()

# Authoring: the same scene written, coefficients included.
foreach(which given reversed)
  run(0 ${HSI_CLI} keyframes ${W}/${which}.json --force --backend cpu -o ${W}/${which}_solved.json)
  if(NOT RUN_OUTPUT MATCHES "reached all targets \\(max error [^)]*\\), certified")
    message(FATAL_ERROR "hsi keyframes on the ${which} scene did not reach and certify its keyframes")
  endif()
endforeach()
file(READ ${W}/given_solved.json a)
file(READ ${W}/reversed_solved.json b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "hsi keyframes wrote another scene when the loops were reversed (compare ${W}/given_solved.json and ${W}/reversed_solved.json)")
endif()

# Interpolation from the files' own keyframes: the same frames.
foreach(which given reversed)
  run(0 ${HSI_CLI} interpolate ${W}/${which}.json --frames 5 --samples 2000 --backend cpu --png-frames 0 -o ${W}/${which}_frames)
endforeach()
file(READ ${W}/given_frames/frames.hsif a HEX)
file(READ ${W}/reversed_frames/frames.hsif b HEX)
if(a STREQUAL "" OR NOT a STREQUAL b)
  message(FATAL_ERROR "hsi interpolate made other frames when the loops were reversed")
endif()
message(STATUS "reversed loops: the same solved scene and the same frames")
