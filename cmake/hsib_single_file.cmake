# cmake -P: writes the stb-style single-file baked runtime hsib.h from the one source
# of truth, engine/include/hsi/baked_runtime.h and engine/src/baked_runtime.c.
# -D: HSIB_HEADER, HSIB_SOURCE, HSIB_OUTPUT
file(READ ${HSIB_HEADER} header)
file(READ ${HSIB_SOURCE} source)
string(FIND "${source}" "#include \"hsi/baked_runtime.h\"\n" at)
if(at LESS 0)
  message(FATAL_ERROR "${HSIB_SOURCE} does not include hsi/baked_runtime.h as expected")
endif()
string(REPLACE "#include \"hsi/baked_runtime.h\"\n" "" source "${source}")
set(text "/* hsib.h: the hsi baked playback runtime in one file, stb style. GENERATED at build
 * time from hsi/baked_runtime.h and its source baked_runtime.c (hsi's engine/ folder):
 * edit those, never this file.
 *
 * Use: in exactly one C (C99) or C++ file of your program write
 *     #define HSIB_IMPLEMENTATION
 *     #include \"hsib.h\"
 * and include \"hsib.h\" without the define wherever else you call it. Link libm.
 * The API and the .hsib format are documented below (the header's own comment). */
${header}
#ifdef HSIB_IMPLEMENTATION
#ifndef HSIB_IMPLEMENTATION_INCLUDED
#define HSIB_IMPLEMENTATION_INCLUDED
${source}
#endif /* HSIB_IMPLEMENTATION_INCLUDED */
#endif /* HSIB_IMPLEMENTATION */
")
# Written only when it changes, so that dependents do not rebuild needlessly.
if(EXISTS ${HSIB_OUTPUT})
  file(READ ${HSIB_OUTPUT} old)
  if(old STREQUAL text)
    return()
  endif()
endif()
file(WRITE ${HSIB_OUTPUT} "${text}")
