# ctest cli_bake_batch: hsi bake over several scenes (issue #23): one .hsib per scene,
# named from the scene files, byte-identical to baking each scene alone (with one
# OpenMP thread, as each batch worker runs) for any --jobs; clashing names refused
# before anything is solved; a scene that cannot be baked is named, the others written.
# -D: HSI_CLI, HSI_ASSETS, HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
set(common --frames 5 --samples 1000)
set(scenes ${HSI_ASSETS}/two_holes.json ${HSI_ASSETS}/annulus.json)

foreach(jobs 1 3)
  run(0 ${HSI_CLI} bake ${scenes} ${common} --jobs ${jobs} -o ${HSI_WORK_DIR}/jobs${jobs})
  if(NOT RUN_OUTPUT MATCHES "baking 2 scene\\(s\\), 10 frames: ${jobs} worker")
    message(FATAL_ERROR "hsi bake (several scenes): the batch line is missing or wrong")
  endif()
  foreach(name two_holes annulus)
    if(NOT RUN_OUTPUT MATCHES "wrote [^\n]*jobs${jobs}/${name}.hsib: 5 frames, [0-9]+ bytes .* 0 uncertified, 0 not converged")
      message(FATAL_ERROR "hsi bake (several scenes): no line for ${name}.hsib")
    endif()
  endforeach()
endforeach()
# Alone, with one OpenMP thread: the same bytes.
foreach(name two_holes annulus)
  run(0 ${CMAKE_COMMAND} -E env OMP_NUM_THREADS=1 ${HSI_CLI} bake ${HSI_ASSETS}/${name}.json ${common} -o ${HSI_WORK_DIR}/${name}.hsib)
  file(SHA256 ${HSI_WORK_DIR}/${name}.hsib alone)
  foreach(jobs 1 3)
    file(SHA256 ${HSI_WORK_DIR}/jobs${jobs}/${name}.hsib batched)
    if(NOT alone STREQUAL batched)
      message(FATAL_ERROR "${name}: baked with --jobs ${jobs} differs from baking it alone")
    endif()
  endforeach()
endforeach()

# Two scenes named alike would write one file: refused, nothing written.
file(MAKE_DIRECTORY ${HSI_WORK_DIR}/other)
file(COPY ${HSI_ASSETS}/annulus.json DESTINATION ${HSI_WORK_DIR}/other)
run(2 ${HSI_CLI} bake ${HSI_ASSETS}/annulus.json ${HSI_WORK_DIR}/other/annulus.json ${common} -o ${HSI_WORK_DIR}/clash)
if(NOT RUN_OUTPUT MATCHES "would both be baked to [^\n]*annulus.hsib")
  message(FATAL_ERROR "hsi bake: a name clash is not refused with a clear message")
endif()
if(EXISTS ${HSI_WORK_DIR}/clash)
  message(FATAL_ERROR "hsi bake: a refused call created its output folder")
endif()

# Several scenes need -o DIR.
run(2 ${HSI_CLI} bake ${scenes} ${common})
if(NOT RUN_OUTPUT MATCHES "give -o DIR")
  message(FATAL_ERROR "hsi bake: several scenes without -o: unexpected message")
endif()

# A broken scene is named; the good one is still written; exit 2 (bad input).
file(WRITE ${HSI_WORK_DIR}/broken.json "{ \"shape\": ")
run(2 ${HSI_CLI} bake ${HSI_WORK_DIR}/broken.json ${HSI_ASSETS}/two_holes.json ${common} -o ${HSI_WORK_DIR}/mixed)
if(NOT RUN_OUTPUT MATCHES "broken.json: not baked" OR NOT RUN_OUTPUT MATCHES "1 of 2 scene\\(s\\) not baked")
  message(FATAL_ERROR "hsi bake: the broken scene is not named")
endif()
if(NOT EXISTS ${HSI_WORK_DIR}/mixed/two_holes.hsib OR EXISTS ${HSI_WORK_DIR}/mixed/broken.hsib)
  message(FATAL_ERROR "hsi bake: the good scene was not written, or the broken one was")
endif()
file(GLOB leftovers ${HSI_WORK_DIR}/mixed/*.tmp)
if(leftovers)
  message(FATAL_ERROR "hsi bake left temporary files: ${leftovers}")
endif()
