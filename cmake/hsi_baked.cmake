# The baked playback runtime as a small static C library, and its install rules
# (component "capi", export set hsiTargets, which runtime/CMakeLists.txt installs with
# the C API). Included from engine/CMakeLists.txt.
include(GNUInstallDirs)

# Baked playback runtime: C99 and libm only, for games that take just it.
add_library(hsi_baked STATIC src/baked_runtime.c)
add_library(hsi::baked ALIAS hsi_baked)
set_target_properties(hsi_baked PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF
                                           POSITION_INDEPENDENT_CODE ON EXPORT_NAME baked)
target_include_directories(hsi_baked PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                            $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_link_libraries(hsi_baked PRIVATE m)
target_link_libraries(hsi_engine PRIVATE hsi_baked)  # the baker writes the runtime's checksums
set_source_files_properties(src/baked_runtime.c PROPERTIES COMPILE_OPTIONS "${HSI_C_WARNINGS}")

install(TARGETS hsi_baked EXPORT hsiTargets COMPONENT capi
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES include/hsi/baked_runtime.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hsi COMPONENT capi)
