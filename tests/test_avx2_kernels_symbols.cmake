# ctest avx2_kernels_symbols: the AVX2 + FMA build of the Newton core's dense linear
# algebra (engine/src/dense_kernels.h) defines nothing the rest of the program could
# pick in place of its own baseline code: every symbol it defines is in the renamed
# Eigen namespace (hsi_eigen_avx2_fma) or is one of its entry points. A std:: or Eigen:: template
# instantiated there (a weak symbol) could be the copy the linker keeps for the whole
# program, and run AVX2 instructions on a processor without them.
# -D: HSI_OBJECTS (the object files, ;-separated), HSI_NM
set(bad "")
set(entry 0)
foreach(object IN LISTS HSI_OBJECTS)
  execute_process(COMMAND ${HSI_NM} -C --defined-only ${object} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nm ${object} failed: ${err}")
  endif()
  string(REPLACE "\n" ";" lines "${out}")
  foreach(line IN LISTS lines)
    if(line MATCHES "^[0-9a-fA-F]+ ([A-Za-z]) (.+)$")
      set(kind ${CMAKE_MATCH_1})
      set(name "${CMAKE_MATCH_2}")
      if(kind MATCHES "^[rtbdn]$" AND NOT name MATCHES "hsi_eigen_avx2_fma")
        # local to the object: read-only data, local code (.cold parts, constants)
      elseif(name MATCHES "^hsi::detail::(hessian_accumulate|cholesky_solve|cholesky_factor|cholesky_solve_factored)_avx2_fma\\(")
        math(EXPR entry "${entry} + 1")
      elseif(name MATCHES "hsi_eigen_avx2_fma::" OR name MATCHES "^DW\\.ref\\.__gxx_personality_v0$")
      else()
        string(APPEND bad "  ${kind} ${name}\n")
      endif()
    endif()
  endforeach()
endforeach()
if(entry EQUAL 0)
  message(FATAL_ERROR "no hsi::detail::*_avx2_fma entry point in ${HSI_OBJECTS}: is this the AVX2 build?")
endif()
if(bad)
  message(FATAL_ERROR "the AVX2 + FMA kernels define symbols the rest of the program could share:\n${bad}")
endif()
message(STATUS "the AVX2 + FMA kernels define only their entry points and hsi_eigen_avx2_fma:: symbols")
