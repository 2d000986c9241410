# Shared by the install tests (test_c_api_install.cmake, test_baked_install.cmake):
# step(NAME COMMAND...) runs a command, prints what it said, fails the test when it
# fails, and leaves its output in STEP_OUTPUT and STEP_ERROR.
function(step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${name}:\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name} failed (${rc})")
  endif()
  set(STEP_OUTPUT "${out}" PARENT_SCOPE)
  set(STEP_ERROR "${err}" PARENT_SCOPE)
endfunction()
