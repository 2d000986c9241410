# Shared by the CLI tests (cmake -P scripts): include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake).

# run(EXPECTED_EXIT_CODE COMMAND ARGS...): runs the command, logs it with its output,
# fails unless it exits with the expected code; its stdout + stderr are left in
# RUN_OUTPUT in the caller's scope.
function(run expect_rc)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ARGN}\n${out}${err}")
  if(NOT rc STREQUAL expect_rc)
    message(FATAL_ERROR "exit code ${rc}, expected ${expect_rc}")
  endif()
  set(RUN_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

# check_report_png(DIR MARKDOWN NAME WIDTH HEIGHT): DIR/NAME is a PNG (signature) of
# WIDTH x HEIGHT pixels (IHDR, big-endian at bytes 16..23), and the Markdown text
# MARKDOWN embeds it as "](NAME)".
function(check_report_png dir md name width height)
  if(NOT EXISTS ${dir}/${name})
    message(FATAL_ERROR "${name} was not written")
  endif()
  file(READ ${dir}/${name} header LIMIT 24 HEX)
  string(SUBSTRING "${header}" 0 16 signature)
  if(NOT signature STREQUAL "89504e470d0a1a0a")
    message(FATAL_ERROR "${name} is not a PNG (starts with ${signature})")
  endif()
  string(SUBSTRING "${header}" 32 8 w)
  string(SUBSTRING "${header}" 40 8 h)
  math(EXPR w "0x${w}")
  math(EXPR h "0x${h}")
  if(NOT w EQUAL width OR NOT h EQUAL height)
    message(FATAL_ERROR "${name} is ${w} x ${h}, expected ${width} x ${height}")
  endif()
  string(FIND "${md}" "](${name})" at)
  if(at LESS 0)
    message(FATAL_ERROR "report.md does not embed ${name}")
  endif()
endfunction()
