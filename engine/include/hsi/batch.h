// Many interpolation sequences solved together by a pool of worker threads (issue #23):
// `hsi bake` over several scenes, the C API's batch, benchmarks. A sequence falls apart
// into runs of frames that do not depend on each other (a run starts where the frame
// is a keyframe itself: keyframe_itself in interpolation.h); the runs of every sequence
// are the work items. Each worker solves a run exactly as Interpolator::sequence does,
// on its own Newton core (one per shape setup it meets, made by the caller's factory:
// the engine knows nothing of CUDA), so the frames are bit-identical to one
// Interpolator::sequence per sequence on the same kind of core with the same OpenMP
// thread count, whatever the number of workers.
#pragma once

#include <chrono>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hsi/interpolation.h"

namespace hsi {

class LockstepBackend;  // hsi/lockstep.h

struct BatchSequence {
  std::string name;                   // names the sequence in errors (e.g. its scene file)
  const ShapeSetup* setup = nullptr;  // read-only, shared by the workers; must outlive solve_batch
  std::vector<double> key_times;      // the keyframes, as Interpolator takes them (certified maps)
  std::vector<HarmonicMap> keyframes;
  InterpolationOptions options;
  std::vector<double> times;          // frame times: increasing, within the keyframes' range (sequence_times())
};

// A worker's Newton core for a setup (which outlives it). Called from the workers,
// concurrently: the factory must be thread-safe (runtime::make_newton_core is).
using BatchCoreFactory = std::function<std::unique_ptr<NewtonCore>(const ShapeSetup&)>;
// A worker's evaluator of f at setup.overlap's breakpoints (the image every frame's
// overlap check tests: the Interpolator's `boundary`), made with its core for the setup
// and lent to each Interpolator it builds; null: the setup's own CPU evaluator. On CUDA
// the image is then made on the GPU (issue #23: on the host with a worker's one thread it
// was 0.94 of a batch frame's 2.1 ms, bench_batch on an H200). Concurrent calls, as above.
using BatchBoundaryFactory = std::function<std::unique_ptr<MeshEvaluator>(const ShapeSetup&)>;

struct BatchOptions {
  int workers = 1;  // W threads, each with its own cores and interpolators
  // OpenMP threads in each worker's parallel regions (the CPU core's sample loops, the
  // certificate): W × this should not exceed the machine's cores. 0: OpenMP's default
  // (OMP_NUM_THREADS, else every core). The CPU core sums its energy in an OpenMP
  // reduction, so its frames depend on this count (not on W) in the last bits.
  int threads_per_worker = 1;
  BatchCoreFactory make_core;  // empty: the CPU core (make_cpu_newton_core)
  BatchBoundaryFactory make_boundary;  // empty: every Interpolator uses the setup's CPU evaluator
  // Lockstep (issue #23): with make_lockstep, each setup's runs are solved by a group of
  // up to `lockstep_systems` threads (instead of the W workers) whose Newton loops are
  // stepped together: each thread's stepper calls are gathered with its group's and
  // served as one batch by the backend's batched stepper (hsi/lockstep.h; on CUDA one
  // launch per stage for the group). Each thread keeps its sequence's Interpolator as a
  // worker does, over a core that is the group's system (make_lockstep_core). The groups
  // of different setups run side by side. threads_per_worker applies to each thread.
  std::function<std::unique_ptr<LockstepBackend>(const ShapeSetup& setup, int systems)> make_lockstep;
  int lockstep_systems = 16;
  // How long a group's posted call waits for the group's other threads (e.g. one building
  // its next sequence's Interpolator) before its round is served without them
  // (LockstepGroup); zero: every round waits for every live thread.
  std::chrono::microseconds lockstep_window{0};
};

// After each frame: the frame, its sequence's index, its index there, and how many
// frames of the whole batch are done of how many. Called from the workers, one call at
// a time, frames of different runs interleaved. Return false to cancel the batch.
using BatchProgress = std::function<bool(const FrameResult& frame, int sequence, int index, size_t done, size_t total)>;

struct BatchSequenceResult {
  std::vector<FrameResult> frames;  // in frame order, as Interpolator::sequence gives them; empty on error
  std::string error;                // empty: solved (its frames carry their own flags); else "NAME: why"
  std::exception_ptr exception;     // what was thrown (an InputError for bad input), for a caller to sort errors by type; null when cancelled
  bool cancelled = false;           // not finished because the progress callback stopped the batch
};

struct BatchStats {
  int workers = 0;               // threads started (at most the number of runs; lockstep: every group's)
  int runs = 0;                  // work items: independent runs over all sequences
  int cores_made = 0;            // Newton cores made by the factory (one per worker and setup it met)
  int interpolators_built = 0;   // each certifies its sequence's keyframes (one per worker and sequence it met)
  double set_up_s = 0;           // time the workers spent making cores and interpolators, summed over workers
  double core_set_up_s = 0;      // the part of set_up_s spent making cores and boundary evaluators (the rest: interpolators)
  double seconds = 0;            // wall-clock time of solve_batch
  bool cancelled = false;        // the progress callback asked to stop; unfinished sequences have an error
};

struct BatchResult {
  std::vector<BatchSequenceResult> sequences;  // one per input sequence, in input order
  BatchStats stats;
  int failed() const;  // sequences with an error
};

// The independent runs of frames at `times` (increasing) for these keyframes: [begin,
// end) index ranges covering every frame in order, a new run at each frame after the
// first that is a keyframe itself.
std::vector<std::pair<int, int>> independent_runs(const std::vector<double>& key_times, const std::vector<KeyTiming>& timing,
                                                  const std::vector<double>& times);

// Solves every sequence. A sequence that cannot be solved (bad input, a keyframe that
// is not certified, a core that cannot be made) gets its error and no frames; the
// others still finish. Frames that are not certified or did not converge are results,
// flagged as in Interpolator::sequence, not errors. Throws InputError only for bad
// options (workers < 1, threads_per_worker < 0).
BatchResult solve_batch(const std::vector<BatchSequence>& sequences, const BatchOptions& options = {},
                        const BatchProgress& progress = {});

}  // namespace hsi
