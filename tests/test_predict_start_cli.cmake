# ctest cli_predict_start: hsi interpolate / bake / export take --predict-start
# (InterpolationOptions::predict_start) and report.json says, per frame, whether its
# solve started from the secant's prediction (predicted_start); a bad value is refused
# by name. -D: HSI_CLI, HSI_SCENE, HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
set(common --frames 9 --samples 1000 --png-frames 0)

# predicted_count(REPORT_JSON VAR): frames of report.json with predicted_start true;
# fails unless every frame is certified and converged.
function(predicted_count json_file var)
  file(READ ${json_file} json)
  string(JSON n LENGTH "${json}" frames)
  math(EXPR last "${n} - 1")
  set(count 0)
  foreach(i RANGE ${last})
    string(JSON p GET "${json}" frames ${i} predicted_start)
    string(JSON c GET "${json}" frames ${i} certified)
    string(JSON v GET "${json}" frames ${i} converged)
    if(NOT c STREQUAL "ON" OR NOT v STREQUAL "ON")
      message(FATAL_ERROR "${json_file}: frame ${i} certified ${c}, converged ${v}")
    endif()
    if(p STREQUAL "ON")
      math(EXPR count "${count} + 1")
    endif()
  endforeach()
  set(${var} ${count} PARENT_SCOPE)
endfunction()

# Off by default: no frame starts from a prediction.
run(0 ${HSI_CLI} interpolate ${HSI_SCENE} ${common} -o ${HSI_WORK_DIR}/off)
predicted_count(${HSI_WORK_DIR}/off/report.json n_off)
if(NOT n_off EQUAL 0)
  message(FATAL_ERROR "hsi interpolate without --predict-start: ${n_off} frames started from a prediction")
endif()
# always: every frame after the interval's first two solved ones may start from the
# secant; some do (a solve from it that fails is redone from the previous frame and
# then says false).
run(0 ${HSI_CLI} interpolate ${HSI_SCENE} ${common} --predict-start always -o ${HSI_WORK_DIR}/always)
predicted_count(${HSI_WORK_DIR}/always/report.json n_always)
if(n_always LESS 1)
  message(FATAL_ERROR "hsi interpolate --predict-start always: no frame started from the secant's prediction")
endif()
# export passes it on too (its report.json is the same report).
run(0 ${HSI_CLI} export ${HSI_SCENE} --frames 9 --samples 1000 --predict-start always --json ${HSI_WORK_DIR}/export.json)
predicted_count(${HSI_WORK_DIR}/export.json n_export)
if(NOT n_export EQUAL n_always)
  message(FATAL_ERROR "hsi export --predict-start always: ${n_export} predicted frames, hsi interpolate ${n_always}")
endif()
run(0 ${HSI_CLI} bake ${HSI_SCENE} --frames 9 --samples 1000 --predict-start auto -o ${HSI_WORK_DIR}/auto.hsib)
# A value that is not one of the three: refused by CLI11 (its code 105), naming the option.
foreach(cmd interpolate bake export)
  execute_process(COMMAND ${HSI_CLI} ${cmd} ${HSI_SCENE} --predict-start secant
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 105 OR NOT "${out}${err}" MATCHES "--predict-start")
    message(FATAL_ERROR "hsi ${cmd} --predict-start secant: exit ${rc}, expected 105 naming the option:\n${out}${err}")
  endif()
endforeach()
