# ctest cli_compare_scene_NAME (label compare_scenes; tests/CMakeLists.txt makes one per
# bundled scene with two or more keyframes): hsi compare on the scene with small settings
# (a ~300-vertex mesh, 400 boundary samples, frames a quarter of a keyframe interval apart,
# so that the side-by-side times are frames of the sequence: seconds per scene), so that
# every scene is known to run
# through all four baselines: report.json has ARAP's, FFMP's, GE's and CCW16's columns per
# frame, summed up, at the side-by-side times and in Tables 3-4 (GE with its iterations),
# the five claims each with a verdict, and report.md their sections. Numbers are checked by
# the [compare] unit tests and cli_compare / cli_compare_fig8; this one checks coverage.
# -D: HSI_CLI, HSI_SCENE, HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
get_filename_component(name ${HSI_SCENE} NAME_WE)
function(fail)
  message(FATAL_ERROR "cli_compare_scene_${name}: ${ARGN}")
endfunction()

file(READ ${HSI_SCENE} scene_text)
string(JSON keys LENGTH "${scene_text}" keyframes)
math(EXPR frames "4 * (${keys} - 1) + 1")
set(dir ${HSI_WORK_DIR}/report)
run(0 ${HSI_CLI} compare ${HSI_SCENE} -o ${dir} --frames ${frames} --table-frames 2 --samples 400 --mesh-vertices 300
    --table3-vertices 300 --no-800k --ratios 0.5 --timing-frames 1 --size 96)
file(READ ${dir}/report.json json)
file(READ ${dir}/report.md md)

foreach(method arap ffmp ge ccw16)
  string(JSON n ERROR_VARIABLE err LENGTH "${json}" sequence ${method} kappa)
  if(err OR NOT n EQUAL frames)
    fail("sequence: ${method} has no kappa per frame (${n} ${err})")
  endif()
  string(JSON kappa ERROR_VARIABLE err GET "${json}" summary ${method} max_kappa)
  string(JSON snap ERROR_VARIABLE err2 GET "${json}" side_by_side 1 ${method} kappa_max)
  if(err OR err2)
    fail("${method}: no summary or side-by-side column (${err} ${err2})")
  endif()
endforeach()
# Ours: every frame certified and converged. (At 100-200 samples two_holes' and bar_holes'
# solves ran into the certificate between samples, 30-100 iterations a frame and frames
# left unconverged, which this test did not see; 400 keeps every scene's solves short.)
foreach(key certified frames not_converged)
  string(JSON ours_${key} GET "${json}" summary ours ${key})
endforeach()
if(NOT ours_certified EQUAL frames OR NOT ours_frames EQUAL frames OR NOT ours_not_converged EQUAL 0)
  fail("ours: ${ours_certified} of ${ours_frames} frames certified, ${ours_not_converged} not converged (expected ${frames}, ${frames}, 0)")
endif()
string(JSON ge_flips GET "${json}" summary ge frames_with_flips)
if(NOT ge_flips EQUAL 0)
  fail("GE: ${ge_flips} frames with flipped triangles (its line search keeps every triangle's orientation)")
endif()
# Table 3: GE at the one resolution, with its iterations; Table 4: every method's time.
string(JSON ge_run GET "${json}" table3_resolution 0 ge_run)
string(JSON ge_ms GET "${json}" table3_resolution 0 ge_ms)
string(JSON ge_it GET "${json}" table3_resolution 0 ge_iterations)
if(NOT ge_run OR NOT ge_ms GREATER 0 OR ge_it LESS 0)
  fail("table 3: GE run ${ge_run}, ${ge_ms} ms, ${ge_it} iterations")
endif()
foreach(key arap_ms ffmp_ms ge_ms ge_iterations ours_solve_ms)
  string(JSON v GET "${json}" table4_per_frame ${key})
  if(NOT v GREATER 0)
    fail("table 4: ${key} = ${v}")
  endif()
endforeach()
# The claims: five, each with a verdict in both reports.
string(JSON nc LENGTH "${json}" claims)
if(NOT nc EQUAL 5)
  fail("${nc} claims, expected 5")
endif()
set(verdicts "")
foreach(i RANGE 4)
  string(JSON id GET "${json}" claims ${i} id)
  string(JSON verdict GET "${json}" claims ${i} verdict)
  string(JSON value GET "${json}" claims ${i} value)
  if(NOT verdict MATCHES "^(holds|does not hold)")
    fail("claim ${id}: verdict '${verdict}'")
  endif()
  string(FIND "${md}" "| **${verdict}** |" at)
  if(at LESS 0)
    fail("report.md does not give claim ${id}'s verdict '${verdict}'")
  endif()
  string(APPEND verdicts "\n  ${id}: ${verdict} (${value})")
endforeach()
foreach(text "## Claims" "| FFMP | " "| GE | " "| GE ms per frame | GE #iter |" "## Table 4: time per frame against ARAP, FFMP and GE"
        "## Side by side (ours, ARAP, FFMP, GE, CCW16")
  string(FIND "${md}" "${text}" at)
  if(at LESS 0)
    fail("report.md has no '${text}'")
  endif()
endforeach()
message(STATUS "${name}:${verdicts}")
