# ctest cli_bad_input: the hsi command line on the bad-input corpus (tests/corpus/scenes).
# Each refused input must exit non-zero with "hsi: error:" and the file and problem
# on stderr, and leave no output behind: the output folder stays absent (or empty)
# and no frames, report, baked or scene file appears.
# -D: HSI_CLI, HSI_CORPUS (tests/corpus/scenes), HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
set(failures "")
# refuse(NAME "expected stderr regex" command...): non-zero exit, message, nothing written under WORK/NAME.
function(refuse name pattern)
  set(out ${HSI_WORK_DIR}/${name})
  string(REPLACE "@OUT@" "${out}" cmd "${ARGN}")
  execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
  message(STATUS "${name}: exit ${rc}: ${stderr}")
  if(rc EQUAL 0)
    list(APPEND failures "${name}: exit code 0")
  endif()
  if(NOT stderr MATCHES "hsi: error: .*${pattern}")
    list(APPEND failures "${name}: stderr does not match '${pattern}': ${stderr}")
  endif()
  if(EXISTS ${out})
    file(GLOB_RECURSE left ${out}/* ${out}.*)
    if(left OR NOT IS_DIRECTORY ${out})
      list(APPEND failures "${name}: left output behind: ${out} ${left}")
    endif()
  endif()
  set(failures "${failures}" PARENT_SCOPE)
endfunction()

set(C ${HSI_CORPUS})
# hsi interpolate: refused while loading, and refused while making the keyframes certified.
refuse(truncated "truncated.json: invalid JSON at line 2" ${HSI_CLI} interpolate ${C}/truncated.json -o @OUT@)
refuse(unknown_version "unsupported version 99" ${HSI_CLI} interpolate ${C}/unknown_version.json -o @OUT@)
refuse(number_overflow "number overflow" ${HSI_CLI} interpolate ${C}/number_overflow.json -o @OUT@)
refuse(bow_tie "outer loop intersects itself" ${HSI_CLI} interpolate ${C}/bow_tie.json -o @OUT@)
refuse(hole_outside "hole 1 lies outside the outer loop" ${HSI_CLI} interpolate ${C}/hole_outside.json -o @OUT@)
refuse(cage_cuts_shape "touches the shape" ${HSI_CLI} interpolate ${C}/cage_cuts_shape.json -o @OUT@)
refuse(handle_outside "handles\\[1\\]: lies outside the shape" ${HSI_CLI} interpolate ${C}/handle_outside.json -o @OUT@)
refuse(phi_wrong_length "keyframes\\[0\\].phi: has 3 coefficients" ${HSI_CLI} interpolate ${C}/keyframe_phi_wrong_length.json -o @OUT@)
refuse(keyframe_folds "keyframe 1 is not locally injective" ${HSI_CLI} interpolate ${C}/keyframe_folds.json -o @OUT@)
refuse(one_keyframe "needs at least two keyframes.*hsi-viewer SCENE.*hsi keyframes SCENE --handle X,Y" ${HSI_CLI} interpolate ${C}/one_keyframe.json -o @OUT@)
# hsi bake and hsi export write nothing for a refused scene.
refuse(bake_folds "keyframe 1 is not locally injective" ${HSI_CLI} bake ${C}/keyframe_folds.json -o @OUT@/seq.hsib)
refuse(bake_bow_tie "outer loop intersects itself" ${HSI_CLI} bake ${C}/bow_tie.json -o @OUT@/seq.hsib)
refuse(export_folds "keyframe 1 is not locally injective" ${HSI_CLI} export ${C}/keyframe_folds.json --gltf @OUT@/a.glb --json @OUT@/r.json)
# hsi import-png: a file that is not a PNG, and a missing one; no scene is written.
file(WRITE ${HSI_WORK_DIR}/not_a.png "hello")
refuse(import_text "not a PNG file" ${HSI_CLI} import-png ${HSI_WORK_DIR}/not_a.png -o @OUT@/s.json)
refuse(import_missing "no such file" ${HSI_CLI} import-png ${HSI_WORK_DIR}/missing.png -o @OUT@/s.json)
# hsi info on a scene that does not parse.
refuse(info_empty "empty.json: invalid JSON" ${HSI_CLI} info ${C}/empty.json)

if(failures)
  string(REPLACE ";" "\n  " failures "${failures}")
  message(FATAL_ERROR "bad input through the CLI:\n  ${failures}")
endif()
