# ctest viewer: hsi-viewer under Xvfb on lavapipe with the Vulkan validation layer
# (any validation message makes the viewer exit with 3):
#  1. opens assets/bar_holes.json, plays 20 frames (each solved live, warm-started),
#     pauses and saves a screenshot; hsi_viewer_check then checks it (frame, not
#     blank, the texture's colours where the shape is, the golden image
#     tests/golden/viewer_bar_holes.png within a perceptual tolerance);
#  2. a script edits: poses the last keyframe by dragging a handle (the
#     point-to-point solve), adds a handle by clicking the shape, toggles the
#     distortion overlay, undoes the handle and saves; the saved scene must hold
#     the pose and not the undone handle, and the smooth timing the script set.
# Without xvfb-run it prints SKIP (the test is skipped), unless HSI_REQUIRE_VIEWER is set.
# -D: HSI_VIEWER, HSI_CHECK, HSI_SCENE, HSI_TEXTURE, HSI_GOLDEN, HSI_WORK_DIR
find_program(XVFB_RUN xvfb-run)
if(NOT XVFB_RUN)
  if(DEFINED ENV{HSI_REQUIRE_VIEWER} AND NOT "$ENV{HSI_REQUIRE_VIEWER}" STREQUAL "0")
    message(FATAL_ERROR "HSI_REQUIRE_VIEWER is set but xvfb-run is missing (Debian: xvfb; scripts/setup.sh installs it)")
  endif()
  message("SKIP: xvfb-run not found (Debian: xvfb): hsi-viewer was not tested")
  return()
endif()
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
set(xvfb ${XVFB_RUN} -a -s "-screen 0 1280x1024x24")

# 1. Playback and a screenshot.
run(0 ${xvfb} ${HSI_VIEWER} ${HSI_SCENE} --validation --width 960 --height 600
    --screenshot-after 20 --screenshot ${HSI_WORK_DIR}/play.png --exit)
run(0 ${HSI_CHECK} ${HSI_WORK_DIR}/play.png ${HSI_GOLDEN} ${HSI_TEXTURE} 20)

# 2. Editing.
file(WRITE ${HSI_WORK_DIR}/edit.txt "seek 60          # the last keyframe (t = 2)
drag 4 1.2 0.7   # pose handle 4
expect-certified
add-handle 0.0 -0.45
key d
screenshot ${HSI_WORK_DIR}/edit.png
undo             # the added handle
timing 0 smooth  # the interval from keyframe 0 to 1 (issue #26)
seek 15
screenshot ${HSI_WORK_DIR}/smooth.png   # waits until frame 15 is solved again and drawn
expect-certified
key n            # the texture filter toggled (linear -> nearest): the same frame looks different
screenshot ${HSI_WORK_DIR}/nearest.png
save ${HSI_WORK_DIR}/saved.json
exit
")
run(0 ${xvfb} ${HSI_VIEWER} ${HSI_SCENE} --validation --width 960 --height 600 --script ${HSI_WORK_DIR}/edit.txt)
if(NOT EXISTS ${HSI_WORK_DIR}/edit.png)
  message(FATAL_ERROR "the editing script wrote no screenshot")
endif()
run(0 ${HSI_CHECK} --differ ${HSI_WORK_DIR}/smooth.png ${HSI_WORK_DIR}/nearest.png)
file(READ ${HSI_WORK_DIR}/saved.json saved)
string(JSON handles LENGTH "${saved}" handles)
if(NOT handles EQUAL 9)
  message(FATAL_ERROR "the saved scene has ${handles} handles: the added one was not undone (expected 9)")
endif()
string(JSON tx GET "${saved}" keyframes 2 targets 4 0)
string(JSON ty GET "${saved}" keyframes 2 targets 4 1)
if(NOT tx EQUAL 1.2 OR NOT ty EQUAL 0.7)
  message(FATAL_ERROR "the saved keyframe 2 has handle 4's target at (${tx}, ${ty}), not the dragged (1.2, 0.7)")
endif()
string(JSON timing0 GET "${saved}" keyframes 0 timing)
string(JSON version GET "${saved}" hsi_scene)
if(NOT timing0 STREQUAL "smooth" OR NOT version EQUAL 2)
  message(FATAL_ERROR "the saved scene has keyframe 0's timing '${timing0}' (version ${version}), not the 'smooth' set by the script (version 2)")
endif()
string(JSON has_phi ERROR_VARIABLE no_phi GET "${saved}" keyframes 2 phi)
if(no_phi)
  message(FATAL_ERROR "the saved keyframe 2 has no coefficients: ${no_phi}")
endif()

# 3. A scene that does not load is refused with a message, before any window work.
file(WRITE ${HSI_WORK_DIR}/bad.json "{\"hsi_scene\": 1, \"shape\": {\"outer\": [[0, 0], [1, 0]]}}")
# No display at all (and no xvfb-run, whose own cleanup can mask the exit code):
# the refusal must come before GLFW is touched.
execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=DISPLAY --unset=WAYLAND_DISPLAY ${HSI_VIEWER} ${HSI_WORK_DIR}/bad.json --validation RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT "${out}${err}" MATCHES "bad.json")
  message(FATAL_ERROR "a bad scene gave exit code ${rc} and: ${out}${err}")
endif()
