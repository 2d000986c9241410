# The C API (hsi/hsi.h) as a shared library, the baked playback runtime as a small
# static C library, and their install rules (component "capi") so that
# find_package(hsi) works from an install prefix. Included from engine/CMakeLists.txt.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(HSI_C_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    $<$<BOOL:${HSI_WARNINGS_AS_ERRORS}>:-Werror>)

# Baked playback runtime: C99 and libm only, for games that take just it.
add_library(hsi_baked STATIC src/baked_runtime.c)
add_library(hsi::baked ALIAS hsi_baked)
set_target_properties(hsi_baked PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF
                                           POSITION_INDEPENDENT_CODE ON EXPORT_NAME baked)
target_include_directories(hsi_baked PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                            $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_link_libraries(hsi_baked PRIVATE m)
target_link_libraries(hsi_engine PRIVATE hsi_baked)  # the baker writes the runtime's checksums

# The C API: only hsi_* and hsib_* are exported (hidden visibility, and the static
# engine's symbols are kept out of the dynamic symbol table).
add_library(hsi_capi SHARED src/c_api.cpp src/baked_runtime.c)
add_library(hsi::hsi ALIAS hsi_capi)
set_target_properties(hsi_capi PROPERTIES
  OUTPUT_NAME hsi EXPORT_NAME hsi
  VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
  C_STANDARD 99 C_VISIBILITY_PRESET hidden CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON
  LIBRARY_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib)
target_compile_definitions(hsi_capi PRIVATE HSI_BUILDING_SHARED)
target_include_directories(hsi_capi PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                           $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_link_libraries(hsi_capi PRIVATE hsi_engine hsi_warnings nlohmann_json::nlohmann_json m)
target_link_options(hsi_capi PRIVATE -Wl,--exclude-libs,ALL -Wl,--no-undefined)
set_source_files_properties(src/baked_runtime.c PROPERTIES COMPILE_OPTIONS "${HSI_C_WARNINGS}")

# Rendering through compute/'s Vulkan renderer, where it is built (called from the
# top-level CMakeLists.txt once compute/ is added).
function(hsi_capi_enable_rendering)
  set_target_properties(hsi_compute PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_sources(hsi_capi PRIVATE ${PROJECT_SOURCE_DIR}/engine/src/c_api_render.cpp)
  target_compile_definitions(hsi_capi PRIVATE HSI_CAPI_RENDER=1)
  target_link_libraries(hsi_capi PRIVATE hsi::compute)
endfunction()

install(TARGETS hsi_capi hsi_baked EXPORT hsiTargets COMPONENT capi
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES include/hsi/hsi.h include/hsi/baked_runtime.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hsi COMPONENT capi)
install(EXPORT hsiTargets NAMESPACE hsi:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hsi COMPONENT capi)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hsiConfig.cmake.in ${PROJECT_BINARY_DIR}/cmake/hsiConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hsi)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/hsiConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cmake/hsiConfig.cmake ${PROJECT_BINARY_DIR}/cmake/hsiConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hsi COMPONENT capi)

# The C example (only hsi/hsi.h); the test suite runs it against the C++ engine.
add_executable(hsi_c_example examples/hsi_example.c)
set_target_properties(hsi_c_example PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF
                                               RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
target_compile_options(hsi_c_example PRIVATE ${HSI_C_WARNINGS})
target_link_libraries(hsi_c_example PRIVATE hsi::hsi)
