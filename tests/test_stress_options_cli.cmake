# ctest bench_stress_options: bench_stress --hessian-ratio refuses what is not a number in
# [0, 1] (nan included) with a message naming the option, before any work; 1 (the Hessian
# over all of G) runs a small slice, every frame certified and converged, and the JSON
# says which ratio ran; --max-iterations 1 lists the unconverged frames and why.
# -D: HSI_BENCH_STRESS, HSI_WORK_DIR
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(MAKE_DIRECTORY ${HSI_WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_test.cmake)
set(W ${HSI_WORK_DIR})
set(slice --sequences annulus/hinge --samples 2000 --frames 3 --projections partproj --jobs 1)

foreach(bad 2 -0.5 nan inf abc 0.5x)
  run(105 ${HSI_BENCH_STRESS} ${slice} --hessian-ratio "${bad}" --json ${W}/bad.json)
  if(NOT RUN_OUTPUT MATCHES "--hessian-ratio: expected a number in \\[0, 1\\]" OR EXISTS ${W}/bad.json)
    message(FATAL_ERROR "--hessian-ratio '${bad}' was not refused with a clear message, or ran")
  endif()
endforeach()

# --projected-decrement-stop: the same refusal (nan included); a value given is the one
# the JSON says ran.
foreach(bad 2 -0.5 nan abc)
  run(105 ${HSI_BENCH_STRESS} ${slice} --projected-decrement-stop "${bad}" --json ${W}/badp.json)
  if(NOT RUN_OUTPUT MATCHES "--projected-decrement-stop: expected a number in \\[0, 1\\]" OR EXISTS ${W}/badp.json)
    message(FATAL_ERROR "--projected-decrement-stop '${bad}' was not refused with a clear message, or ran")
  endif()
endforeach()
run(0 ${HSI_BENCH_STRESS} ${slice} --projected-decrement-stop 0 --json ${W}/p0.json)
file(READ ${W}/p0.json j)
string(JSON pds GET "${j}" options projected_decrement_stop)
string(JSON certified GET "${j}" total 0 certified)
string(JSON frames GET "${j}" total 0 frames)
if(NOT pds EQUAL 0 OR NOT certified EQUAL frames)
  message(FATAL_ERROR "--projected-decrement-stop 0: the JSON says ${pds}, ${certified} of ${frames} certified")
endif()

# --frames takes counts >= 1 and 'mid' (each interval's midpoint solved cold).
foreach(bad 0 -3 abc 5x mid2)
  run(2 ${HSI_BENCH_STRESS} --sequences annulus/hinge --samples 2000 --frames "${bad}" --jobs 1 --json ${W}/badf.json)
  if(NOT RUN_OUTPUT MATCHES "--frames: '${bad}' is not a frame count >= 1 or 'mid'" OR EXISTS ${W}/badf.json)
    message(FATAL_ERROR "--frames '${bad}' was not refused with a clear message, or ran")
  endif()
endforeach()
run(0 ${HSI_BENCH_STRESS} --sequences annulus/hinge --samples 2000 --frames mid --projections partproj --jobs 1 --json ${W}/mid.json)
file(READ ${W}/mid.json j)
string(JSON fpi GET "${j}" total 0 frames_per_interval)
string(JSON frames GET "${j}" total 0 frames)
string(JSON certified GET "${j}" total 0 certified)
if(NOT fpi STREQUAL "mid" OR NOT frames EQUAL 1 OR NOT certified EQUAL 1)
  message(FATAL_ERROR "--frames mid: frames_per_interval '${fpi}', ${frames} frames (want 1: annulus/hinge has one interval), ${certified} certified")
endif()

run(0 ${HSI_BENCH_STRESS} ${slice} --hessian-ratio 1 --json ${W}/r1.json)
file(READ ${W}/r1.json j)
string(JSON ratio GET "${j}" options hessian_ratio)
string(JSON frames GET "${j}" total 0 frames)
string(JSON certified GET "${j}" total 0 certified)
string(JSON not_converged GET "${j}" total 0 not_converged)
string(JSON failed GET "${j}" total 0 failed_runs)
if(NOT ratio EQUAL 1 OR NOT frames EQUAL 2 OR NOT certified EQUAL frames OR NOT not_converged EQUAL 0 OR NOT failed EQUAL 0)
  message(FATAL_ERROR "--hessian-ratio 1: ratio ${ratio}, ${frames} frames (want 2), ${certified} certified, ${not_converged} not converged, ${failed} failed runs")
endif()

# A run names each frame that did not converge and why (NewtonStop): one iteration a frame.
run(0 ${HSI_BENCH_STRESS} ${slice} --max-iterations 1 --json ${W}/cap.json)
file(READ ${W}/cap.json j)
string(JSON not_converged GET "${j}" total 0 not_converged)
string(JSON listed LENGTH "${j}" total 0 unconverged_frames)
string(JSON stop0 GET "${j}" total 0 unconverged_frames 0 stop)
if(not_converged LESS 1 OR NOT listed EQUAL not_converged OR NOT stop0 STREQUAL "iteration limit"
   OR NOT RUN_OUTPUT MATCHES "not converged: t=[0-9.]+ iteration limit after 1 it")
  message(FATAL_ERROR "--max-iterations 1: ${not_converged} not converged, ${listed} listed, first stop '${stop0}', or no progress-line list")
endif()

# --exact-samples: a bad name refused before any work; all runs the slice, the JSON says
# which ran; --trace marks the chord steps the runs take (a frame after the first).
run(105 ${HSI_BENCH_STRESS} ${slice} --exact-samples G --json ${W}/badx.json)
if(NOT RUN_OUTPUT MATCHES "--exact-samples" OR EXISTS ${W}/badx.json)
  message(FATAL_ERROR "--exact-samples G was not refused with a message naming the option, or ran")
endif()
run(0 ${HSI_BENCH_STRESS} ${slice} --exact-samples all --predict-start off --trace --json ${W}/all.json)
file(READ ${W}/all.json j)
string(JSON exact GET "${j}" options exact_samples)
string(JSON certified GET "${j}" total 0 certified)
string(JSON not_converged GET "${j}" total 0 not_converged)
if(NOT exact STREQUAL "all" OR NOT certified EQUAL 2 OR NOT not_converged EQUAL 0)
  message(FATAL_ERROR "--exact-samples all: options say '${exact}', ${certified} certified (want 2), ${not_converged} not converged")
endif()
if(NOT RUN_OUTPUT MATCHES "step [0-9.e+-]+ chord " OR NOT RUN_OUTPUT MATCHES " exact G dec2")
  message(FATAL_ERROR "--trace shows no chord step or no exact system over G:\n${RUN_OUTPUT}")
endif()
# --predict-start: refused outside its names; "always" starts the second frame of the
# interval from the secant (the trace says so), recorded in the JSON options; the
# chord-free predicted solve still converges and certifies both frames.
run(105 ${HSI_BENCH_STRESS} ${slice} --predict-start secant --json ${W}/badq.json)
if(NOT RUN_OUTPUT MATCHES "--predict-start" OR EXISTS ${W}/badq.json)
  message(FATAL_ERROR "--predict-start secant was not refused with a message naming the option, or ran")
endif()
run(0 ${HSI_BENCH_STRESS} ${slice} --predict-start always --trace --json ${W}/pred.json)
file(READ ${W}/pred.json j)
string(JSON mode GET "${j}" options predict_start)
string(JSON certified GET "${j}" total 0 certified)
string(JSON not_converged GET "${j}" total 0 not_converged)
if(NOT mode STREQUAL "always" OR NOT certified EQUAL 2 OR NOT not_converged EQUAL 0)
  message(FATAL_ERROR "--predict-start always: options say '${mode}', ${certified} certified (want 2), ${not_converged} not converged")
endif()
if(NOT RUN_OUTPUT MATCHES "from the secant's start")
  message(FATAL_ERROR "--predict-start always: the trace shows no frame from the secant's start:\n${RUN_OUTPUT}")
endif()
