# ctest capi_install: installs the "capi" component to a temporary prefix, then
# configures, builds and runs tests/c_api_consumer against it with find_package(hsi).
# -D: HSI_BUILD_DIR, HSI_WORK_DIR, HSI_CONSUMER_DIR, HSI_SCENE, HSI_GENERATOR, HSI_VERSION (the project's)
file(REMOVE_RECURSE ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/install_step.cmake)
step(install ${CMAKE_COMMAND} --install ${HSI_BUILD_DIR} --prefix ${HSI_WORK_DIR}/prefix --component capi)
foreach(f include/hsi/hsi.h include/hsi/baked_runtime.h lib/cmake/hsi/hsiConfig.cmake lib/cmake/hsi/hsiConfigVersion.cmake)
  if(NOT EXISTS ${HSI_WORK_DIR}/prefix/${f})
    message(FATAL_ERROR "install: ${f} is missing")
  endif()
endforeach()
step(configure ${CMAKE_COMMAND} -S ${HSI_CONSUMER_DIR} -B ${HSI_WORK_DIR}/build -G ${HSI_GENERATOR}
     -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${HSI_WORK_DIR}/prefix
     # A sanitizer build installs instrumented static libraries: link the consumer as it was.
     "-DCMAKE_EXE_LINKER_FLAGS=${HSI_CONSUMER_LINK_FLAGS}")
step(build ${CMAKE_COMMAND} --build ${HSI_WORK_DIR}/build)
step(consumer ${HSI_WORK_DIR}/build/consumer ${HSI_SCENE} ${HSI_WORK_DIR}/seq.hsib)
if(NOT STEP_OUTPUT MATCHES "consumer ok: hsi ${HSI_VERSION}, 3 frames baked")
  message(FATAL_ERROR "consumer: unexpected output")
endif()
step(player ${HSI_WORK_DIR}/build/player ${HSI_WORK_DIR}/seq.hsib)
if(NOT STEP_OUTPUT MATCHES "player ok: 3 frames")
  message(FATAL_ERROR "player: unexpected output")
endif()
