# ctest cli_no_cuda_libraries_at_start: the hsi tool's load-time dependencies (resolved,
# transitively) include no cuBLAS, cuBLASLt or cuSOLVER: the CUDA backend opens them on
# first use (cuda/src/lazy_libraries.cpp). Linked, they made every command, even an
# import of a 30 x 38 sprite, take ~265 MB. -D: HSI_CLI
file(GET_RUNTIME_DEPENDENCIES EXECUTABLES ${HSI_CLI}
     RESOLVED_DEPENDENCIES_VAR resolved UNRESOLVED_DEPENDENCIES_VAR unresolved)
foreach(lib ${resolved} ${unresolved})
  get_filename_component(name "${lib}" NAME)
  if(name MATCHES "^lib(cublas|cublasLt|cusolver|cusparse)\\.")
    message(FATAL_ERROR "${HSI_CLI} loads ${name} at start; the CUDA backend must open it on first use")
  endif()
endforeach()
list(LENGTH resolved n)
message(STATUS "${HSI_CLI}: ${n} shared libraries at start, no cuBLAS / cuSOLVER")
