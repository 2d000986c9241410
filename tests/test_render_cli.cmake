# ctest cli_render: hsi interpolate then hsi render end to end on a bundled scene
# (few frames, few samples, small images) under the Vulkan validation layer: the
# numbered PNGs and the contact sheet are written, PNGs of the requested size, and
# bad input (no frames file, frames of another scene, a missing texture) fails with
# exit code 2 and a message naming the problem; --rasterizer picks each path, and an
# unknown one is refused (CLI11's exit code 105).
# -D: HSI_CLI, HSI_SCENE, HSI_OTHER_SCENE, HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
set(frames ${HSI_WORK_DIR}/frames)
run(0 ${HSI_CLI} interpolate ${HSI_SCENE} --frames 4 --samples 1000 --png-frames 0 -o ${frames})
run(0 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/render --size 160x120
    --overlay distortion,boundary,handles --validation)
foreach(f frame_0000.png frame_0001.png frame_0002.png frame_0003.png contact_sheet.png)
  if(NOT EXISTS ${HSI_WORK_DIR}/render/${f})
    message(FATAL_ERROR "hsi render did not write ${f}")
  endif()
endforeach()
# PNG header: width and height, big-endian, at bytes 16..23.
file(READ ${HSI_WORK_DIR}/render/frame_0002.png header LIMIT 24 HEX)
string(SUBSTRING "${header}" 32 16 size)
if(NOT size STREQUAL "000000a000000078")  # 160 x 120
  message(FATAL_ERROR "frame_0002.png is not 160 x 120 (IHDR size ${size})")
endif()
run(0 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/one --frames 3 --no-contact-sheet --no-texture --size 96)
if(EXISTS ${HSI_WORK_DIR}/one/contact_sheet.png OR NOT EXISTS ${HSI_WORK_DIR}/one/frame_0003.png)
  message(FATAL_ERROR "--frames 3 --no-contact-sheet wrote the wrong files")
endif()

# Each rasterizer by name (lavapipe picks graphics by itself), under validation.
run(0 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/compute --frames 1 --no-contact-sheet --size 96
    --rasterizer compute --validation)
if(NOT RUN_OUTPUT MATCHES "compute rasterizer" OR NOT EXISTS ${HSI_WORK_DIR}/compute/frame_0001.png)
  message(FATAL_ERROR "--rasterizer compute did not render with the compute rasterizer")
endif()
# The texture filter: the scene's (linear here) unless --filter says otherwise, named in the output.
if(NOT RUN_OUTPUT MATCHES "compute rasterizer, linear texture filtering")
  message(FATAL_ERROR "hsi render does not say which texture filter it uses")
endif()
foreach(ras compute graphics)
  run(0 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/nearest_${ras} --frames 1 --no-contact-sheet --size 96
      --rasterizer ${ras} --filter nearest --validation)
  if(NOT RUN_OUTPUT MATCHES "${ras} rasterizer, nearest texture filtering")
    message(FATAL_ERROR "hsi render --filter nearest --rasterizer ${ras} did not render with nearest filtering")
  endif()
endforeach()
run(105 ${HSI_CLI} render ${HSI_SCENE} ${frames} -o ${HSI_WORK_DIR}/bad --rasterizer fast)
if(NOT RUN_OUTPUT MATCHES "--rasterizer: fast not in")
  message(FATAL_ERROR "an unknown rasterizer was not refused by name")
endif()

run(2 ${HSI_CLI} render ${HSI_SCENE} ${HSI_WORK_DIR} -o ${HSI_WORK_DIR}/bad)
if(NOT RUN_OUTPUT MATCHES "frames.hsif not found")
  message(FATAL_ERROR "a missing frames file was not named")
endif()
run(2 ${HSI_CLI} render ${HSI_OTHER_SCENE} ${frames} -o ${HSI_WORK_DIR}/bad)
if(NOT RUN_OUTPUT MATCHES "does not belong to")
  message(FATAL_ERROR "frames of another scene were not refused")
endif()
file(READ ${HSI_SCENE} scene_text)
string(REGEX REPLACE "\"texture\": \"[^\"]*\"" "\"texture\": \"no_such_texture.png\"" scene_text "${scene_text}")
file(WRITE ${HSI_WORK_DIR}/notex.json "${scene_text}")
# The cage is in the scene file, so the frames still match; only the texture is missing.
run(2 ${HSI_CLI} render ${HSI_WORK_DIR}/notex.json ${frames} -o ${HSI_WORK_DIR}/bad)
if(NOT RUN_OUTPUT MATCHES "no_such_texture.png.*--no-texture")
  message(FATAL_ERROR "a missing texture was not named")
endif()
