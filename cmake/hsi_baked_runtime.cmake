# What a game engine takes of the baked runtime beyond the hsi_baked library
# (cmake/hsi_capi.cmake): the single-file hsib.h generated from the runtime's one
# source, the GLSL playback shader, pkg-config files, the installed docs the headers
# cite, and libhsi's export list. Included from runtime/CMakeLists.txt, after libhsi (hsi_capi) is defined.
include(GNUInstallDirs)

# hsib.h (stb style), regenerated whenever the runtime's header or source changes.
set(HSIB_SINGLE_FILE ${PROJECT_BINARY_DIR}/include/hsib.h)
add_custom_command(OUTPUT ${HSIB_SINGLE_FILE}
  COMMAND ${CMAKE_COMMAND} -DHSIB_HEADER=${PROJECT_SOURCE_DIR}/engine/include/hsi/baked_runtime.h
          -DHSIB_SOURCE=${PROJECT_SOURCE_DIR}/engine/src/baked_runtime.c -DHSIB_OUTPUT=${HSIB_SINGLE_FILE}
          -P ${PROJECT_SOURCE_DIR}/cmake/hsib_single_file.cmake
  DEPENDS ${PROJECT_SOURCE_DIR}/engine/include/hsi/baked_runtime.h ${PROJECT_SOURCE_DIR}/engine/src/baked_runtime.c
          ${PROJECT_SOURCE_DIR}/cmake/hsib_single_file.cmake
  COMMENT "Generating the single-file baked runtime hsib.h")
add_custom_target(hsib_single_file ALL DEPENDS ${HSIB_SINGLE_FILE})
add_library(hsib_header INTERFACE)  # for in-tree users of hsib.h
add_library(hsi::hsib_header ALIAS hsib_header)
target_include_directories(hsib_header INTERFACE $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>)
add_dependencies(hsib_header hsib_single_file)

# libhsi exports hsi_* and hsib_* only (checked by the ctest capi_exports).
if(TARGET hsi_capi)
  target_link_options(hsi_capi PRIVATE -Wl,--version-script=${PROJECT_SOURCE_DIR}/cmake/hsi_exports.map)
  set_property(TARGET hsi_capi APPEND PROPERTY LINK_DEPENDS ${PROJECT_SOURCE_DIR}/cmake/hsi_exports.map)
endif()

# pkg-config: hsi (libhsi) and hsi-baked (the static runtime alone), relocatable.
file(RELATIVE_PATH HSI_PC_TO_PREFIX ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" HSI_PC_TO_PREFIX "${HSI_PC_TO_PREFIX}")
foreach(pc hsi hsi-baked)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${PROJECT_BINARY_DIR}/pkgconfig/${pc}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${pc}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT capi)
endforeach()

install(FILES ${HSIB_SINGLE_FILE} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT capi)
# The installed headers cite README.md (scene files, the C API, baked playback): it is installed with them.
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT capi)
# The GPU playback shader and its per-API preambles, beside the runtime's header.
install(FILES ${PROJECT_SOURCE_DIR}/shaders/hsib_playback.glsl ${PROJECT_SOURCE_DIR}/shaders/hsib_preamble_vulkan.glsl
              ${PROJECT_SOURCE_DIR}/shaders/hsib_preamble_gl.glsl DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hsi COMPONENT capi)
