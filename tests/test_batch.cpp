// Batched solving (hsi/batch.h): the runs between keyframe frames are independent, so a
// pool of workers gives every sequence's frames bit-identical to Interpolator::sequence;
// a sequence that fails is named while the others finish.
#include <catch2/catch.hpp>
#include <atomic>
#include <chrono>
#include <map>
#include <thread>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "bench_scenes.h"
#include "frame_compare.h"
#include "hsi/batch.h"
#include "hsi/keyframes.h"
#include "hsi/lockstep.h"
#include "hsi/runtime/backend.h"

using namespace hsi;
using hsi::test::require_same;  // every field a frame reports, exactly (timings aside)
using Catch::Matchers::Contains;

namespace {

// A bundled scene at |G| = 1000, its keyframes certified (the benchmarks' loader).
bench::Loaded& bundled(const std::string& name) {
  static std::map<std::string, bench::Loaded> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, bench::load(std::string(HSI_ASSETS_DIR) + "/" + name + ".json", 1000, 0.2)).first;
  return it->second;
}

BatchSequence sequence_of(const std::string& name, const std::vector<KeyTiming>& timing, std::vector<double> times) {
  bench::Loaded& S = bundled(name);
  BatchSequence q;
  q.name = name;
  q.setup = S.setup.get();
  q.key_times = S.times;
  q.keyframes = S.maps;
  q.options.timing = timing;
  q.times = std::move(times);
  return q;
}

// One OpenMP thread on this thread while alive: the CPU core's energy is an OpenMP sum,
// whose rounding follows the thread count (BatchOptions::threads_per_worker = 1).
struct OneThread {
#ifdef _OPENMP
  int before = omp_get_max_threads();
  OneThread() { omp_set_num_threads(1); }
  ~OneThread() { omp_set_num_threads(before); }
#endif
};

}  // namespace

TEST_CASE("independent runs start at every frame that is a keyframe itself", "[batch]") {
  const std::vector<double> keys{0.0, 1.0, 2.0};
  // 5 uniform frames over [0, 2]: 0, 0.5, 1 (keyframe 1), 1.5, 2 (keyframe 2).
  CHECK(independent_runs(keys, {}, sequence_times(keys, 5)) == std::vector<std::pair<int, int>>{{0, 2}, {2, 4}, {4, 5}});
  // 4 uniform frames miss keyframe 1: the sequence crosses it warm-started, one run until t = 2.
  CHECK(independent_runs(keys, {}, sequence_times(keys, 4)) == std::vector<std::pair<int, int>>{{0, 3}, {3, 4}});
  // Hold from keyframe 0: every frame of the first interval is keyframe 0 itself.
  CHECK(independent_runs(keys, {KeyTiming::Hold, KeyTiming::Linear, KeyTiming::Linear}, sequence_times(keys, 5)) ==
        std::vector<std::pair<int, int>>{{0, 1}, {1, 2}, {2, 4}, {4, 5}});
}

TEST_CASE("a batch gives every sequence's frames bit-identical to Interpolator::sequence, for 1, 3 and 64 workers", "[batch]") {
  std::vector<BatchSequence> sequences;
  sequences.push_back(sequence_of("annulus", {KeyTiming::Linear, KeyTiming::Hold, KeyTiming::Linear}, frame_times({0, 1, 2}, 4)));
  sequences.push_back(sequence_of("glyph_8", {KeyTiming::Smooth}, frame_times({0, 1, 2}, 5)));
  sequences.push_back(sequence_of("arm", {}, sequence_times({0, 3}, 8)));      // misses keyframes 1 and 2
  sequences.push_back(sequence_of("annulus", {}, sequence_times({0, 2}, 7)));  // same setup as the first: a worker's core is reused
  REQUIRE(bundled("arm").times.size() == 4);
  // Exact systems over all of G (the CUDA core's choice: a move to all of G is carried to
  // the next frames) and every start predicted: neither may cross a keyframe, or the runs
  // the batch cuts there differ from the whole sequence.
  sequences.push_back(sequence_of("glyph_8", {KeyTiming::Smooth}, frame_times({0, 1, 2}, 5)));
  sequences.back().options.exact_samples = ExactSamples::All;
  sequences.back().options.predict_start = PredictStart::Always;

  std::vector<std::vector<FrameResult>> reference;
  {
    const OneThread one;
    for (const BatchSequence& q : sequences) {
      Interpolator I(*q.setup, q.key_times, q.keyframes, q.options);
      reference.push_back(I.sequence(q.times));
      for (const FrameResult& f : reference.back()) CHECK(I.keyframe_itself(f.t) == (f.keyframe || f.held));
    }
  }
  int held = 0, smooth_solved = 0;
  for (const FrameResult& f : reference[0]) held += f.held;
  for (const FrameResult& f : reference[1]) smooth_solved += !f.keyframe;
  REQUIRE(held > 0);
  REQUIRE(smooth_solved > 0);

  for (int workers : {1, 3, 64}) {  // 64: more workers than runs
    INFO("workers = " << workers);
    BatchOptions o;
    o.workers = workers;
    size_t calls = 0, last_total = 0;
    std::vector<std::vector<char>> seen(sequences.size());
    for (size_t s = 0; s < sequences.size(); ++s) seen[s].assign(sequences[s].times.size(), 0);
    const BatchResult r = solve_batch(sequences, o, [&](const FrameResult&, int s, int i, size_t, size_t total) {
      ++calls;
      last_total = total;
      ++seen[static_cast<size_t>(s)][static_cast<size_t>(i)];
      return true;
    });
    REQUIRE(r.failed() == 0);
    CHECK(r.stats.workers == std::min(workers, r.stats.runs));
    CHECK(r.stats.runs > static_cast<int>(sequences.size()));  // the frame_times sequences split at their keyframes
    size_t frames = 0;
    for (size_t s = 0; s < sequences.size(); ++s) {
      REQUIRE(r.sequences[s].frames.size() == reference[s].size());
      for (size_t i = 0; i < reference[s].size(); ++i) require_same(r.sequences[s].frames[i], reference[s][i]);
      for (char c : seen[s]) CHECK(c == 1);  // every frame reported once
      frames += reference[s].size();
    }
    CHECK(calls == frames);
    CHECK(last_total == frames);
  }
}

TEST_CASE("a lockstep batch gives every sequence's frames bit-identical to Interpolator::sequence", "[batch][lockstep]") {
  // The serial backend (each system's own CPU core and stepper, a batch's calls one after
  // another): the loop and the group's gathering of calls change nothing in a frame.
  std::vector<BatchSequence> sequences;
  sequences.push_back(sequence_of("annulus", {KeyTiming::Linear, KeyTiming::Hold, KeyTiming::Linear}, frame_times({0, 1, 2}, 4)));
  sequences.push_back(sequence_of("glyph_8", {KeyTiming::Smooth}, frame_times({0, 1, 2}, 5)));
  sequences.push_back(sequence_of("annulus", {}, sequence_times({0, 2}, 7)));  // the first's setup: one group
  sequences.push_back(sequence_of("glyph_8", {}, frame_times({0, 1, 2}, 4)));
  sequences.back().options.exact_samples = ExactSamples::All;
  std::vector<std::vector<FrameResult>> reference;
  {
    const OneThread one;
    for (const BatchSequence& q : sequences) {
      Interpolator I(*q.setup, q.key_times, q.keyframes, q.options);
      reference.push_back(I.sequence(q.times));
    }
  }
  for (const auto& [systems, window_us] : {std::pair{1, 0}, {3, 0}, {16, 0}, {3, 300}}) {  // 16: more systems than a setup's runs
    INFO("lockstep systems = " << systems << ", window " << window_us << " us");
    BatchOptions o;
    o.lockstep_systems = systems;
    o.lockstep_window = std::chrono::microseconds(window_us);  // rounds served without the threads away: the same frames
    o.make_lockstep = [](const ShapeSetup& setup, int n) {
      return make_serial_lockstep_backend(setup, n, [&setup] { return make_cpu_newton_core(setup.D_G, setup.H); });
    };
    std::atomic<size_t> calls{0};
    const BatchResult r = solve_batch(sequences, o, [&](const FrameResult&, int, int, size_t, size_t) {
      ++calls;
      return true;
    });
    for (const auto& q : r.sequences) CHECK(q.error == "");
    REQUIRE(r.failed() == 0);
    CHECK(r.stats.cores_made == 2);  // one backend per setup
    size_t frames = 0;
    for (size_t s = 0; s < sequences.size(); ++s) {
      REQUIRE(r.sequences[s].frames.size() == reference[s].size());
      for (size_t i = 0; i < reference[s].size(); ++i) require_same(r.sequences[s].frames[i], reference[s][i]);
      frames += reference[s].size();
    }
    CHECK(calls.load() == frames);
  }
  SECTION("a backend that cannot be made fails its setup's sequences alone, named") {
    BatchOptions o;
    o.make_lockstep = [](const ShapeSetup& setup, int n) -> std::unique_ptr<LockstepBackend> {
      if (&setup == bundled("glyph_8").setup.get()) throw InputError("no backend for this shape");
      return make_serial_lockstep_backend(setup, n, [&setup] { return make_cpu_newton_core(setup.D_G, setup.H); });
    };
    const BatchResult r = solve_batch(sequences, o);
    CHECK(r.failed() == 2);
    CHECK(r.sequences[0].error == "");
    CHECK_THAT(r.sequences[1].error, Contains("glyph_8") && Contains("no backend for this shape"));
    CHECK_THAT(r.sequences[3].error, Contains("no backend for this shape"));
    for (size_t i = 0; i < reference[2].size(); ++i) require_same(r.sequences[2].frames[i], reference[2][i]);
    o.lockstep_systems = 0;
    CHECK_THROWS_WITH(solve_batch(sequences, o), Contains("at least 1 system"));
    o.lockstep_systems = 2;
    o.lockstep_window = std::chrono::microseconds(-1);
    CHECK_THROWS_WITH(solve_batch(sequences, o), Contains("lockstep window cannot be negative (got -1 us)"));
  }
}

TEST_CASE("a sequence that fails is named while the others finish", "[batch]") {
  std::vector<BatchSequence> sequences;
  sequences.push_back(sequence_of("two_holes", {}, sequence_times({0, 2}, 5)));
  BatchSequence folded = sequence_of("two_holes", {}, sequence_times({0, 2}, 5));
  folded.name = "folded.json";
  folded.keyframes[1] = affine_map(folded.setup->cage, 1.0, 1.3, 0.0);  // |f_zbar| > |f_z|: folds everywhere
  sequences.push_back(folded);
  BatchSequence late = sequence_of("annulus", {}, {0.0, 0.5, 2.5});
  late.name = "late.json";
  sequences.push_back(late);
  sequences.push_back(sequence_of("annulus", {}, sequence_times({0, 2}, 5)));
  for (int workers : {1, 3}) {
    BatchOptions o;
    o.workers = workers;
    const BatchResult r = solve_batch(sequences, o);
    CHECK(r.failed() == 2);
    CHECK(r.sequences[0].error.empty());
    CHECK(r.sequences[0].frames.size() == 5);
    CHECK_THAT(r.sequences[1].error, Contains("folded.json") && Contains("keyframe 1 is not locally injective"));
    CHECK(r.sequences[1].frames.empty());
    CHECK_THROWS_AS(std::rethrow_exception(r.sequences[1].exception), InputError);  // callers sort errors by type
    CHECK_FALSE(r.sequences[1].cancelled);
    CHECK_THAT(r.sequences[2].error, Contains("late.json") && Contains("time 2 is 2.5"));
    CHECK(r.sequences[3].error.empty());
    for (const FrameResult& f : r.sequences[3].frames) CHECK(f.certified);
  }
  BatchOptions none;
  none.workers = 0;
  CHECK_THROWS_WITH(solve_batch(sequences, none), Contains("at least 1 worker"));
}

TEST_CASE("a batch's boundary evaluators: one per worker and shape, lent to its interpolators; a wrong one is named", "[batch]") {
  std::vector<BatchSequence> sequences;
  sequences.push_back(sequence_of("annulus", {}, sequence_times({0, 2}, 6)));
  sequences.push_back(sequence_of("two_holes", {}, sequence_times({0, 2}, 5)));
  sequences.push_back(sequence_of("annulus", {}, frame_times({0, 1, 2}, 3)));  // the first one's shape again
  BatchOptions plain;
  plain.workers = 1;
  const BatchResult reference = solve_batch(sequences, plain);
  REQUIRE(reference.failed() == 0);
  // The setup's own CPU evaluator and one made anew at its breakpoints give the same image:
  // the frames are those of the batch without a factory, bit for bit.
  std::atomic<int> made{0};
  BatchOptions lent = plain;
  lent.make_boundary = [&](const ShapeSetup& setup) {
    ++made;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the stats must count it as the cores' set-up
    return make_cpu_mesh_evaluator(setup.cage, setup.overlap.breakpoints().points);
  };
  const BatchResult r = solve_batch(sequences, lent);
  REQUIRE(r.failed() == 0);
  CHECK(made.load() == r.stats.cores_made);  // with each core, not with each Interpolator
  CHECK(r.stats.core_set_up_s >= 0.02 * made.load());
  CHECK(r.stats.core_set_up_s < r.stats.set_up_s);  // the interpolators' part is the rest
  CHECK(r.stats.interpolators_built > made.load());
  for (size_t s = 0; s < sequences.size(); ++s) {
    REQUIRE(r.sequences[s].frames.size() == reference.sequences[s].frames.size());
    for (size_t i = 0; i < r.sequences[s].frames.size(); ++i) require_same(r.sequences[s].frames[i], reference.sequences[s].frames[i]);
  }
  // An evaluator made for other points fails its sequences with the reason; none crashes.
  BatchOptions wrong = plain;
  wrong.make_boundary = [](const ShapeSetup& setup) {
    const std::vector<cd> few(setup.overlap.breakpoints().points.begin(), setup.overlap.breakpoints().points.begin() + 3);
    return make_cpu_mesh_evaluator(setup.cage, few);
  };
  const BatchResult bad = solve_batch(sequences, wrong);
  CHECK(bad.failed() == 3);
  CHECK_THAT(bad.sequences[0].error, Contains("annulus") && Contains("boundary evaluator is made for 3"));
}

TEST_CASE("a batch cancelled by its progress callback reports its unfinished sequences", "[batch]") {
  std::vector<BatchSequence> sequences;
  for (int k = 0; k < 3; ++k) sequences.push_back(sequence_of("two_holes", {}, sequence_times({0, 2}, 6)));
  int calls = 0;
  const BatchResult r = solve_batch(sequences, BatchOptions{}, [&](const FrameResult&, int, int, size_t, size_t) {
    return ++calls < 3;
  });
  CHECK(r.stats.cancelled);
  CHECK(calls == 3);
  CHECK(r.failed() == 3);  // one worker: the first sequence was stopped in its first run
  CHECK_THAT(r.sequences[0].error, Contains("cancelled"));
  CHECK(r.sequences[0].cancelled);
  CHECK_FALSE(r.sequences[0].exception);
}

TEST_CASE("a batch on CUDA cores gives the frames of Interpolator::sequence on a CUDA core (skips without a GPU)", "[batch][cuda]") {
  const runtime::CudaStatus cuda = runtime::cuda_status();
  if (!cuda.available) {
    WARN("no CUDA core here: " << cuda.detail);
    return;
  }
  // The batch's factories as hsi bake and the C API set them (the core, the image on the
  // GPU), against one Interpolator per sequence made as hsi interpolate makes it.
  BatchOptions o;
  runtime::set_batch_backend(o, runtime::Backend::Cuda, cuda);
  REQUIRE(o.make_boundary);
  std::vector<BatchSequence> sequences;
  sequences.push_back(sequence_of("annulus", {KeyTiming::Linear, KeyTiming::Hold, KeyTiming::Linear}, frame_times({0, 1, 2}, 4)));
  sequences.push_back(sequence_of("glyph_8", {KeyTiming::Smooth}, frame_times({0, 1, 2}, 5)));
  sequences.push_back(sequence_of("two_holes", {}, sequence_times({0, 2}, 9)));
  std::vector<std::vector<FrameResult>> reference;
  {
    const OneThread one;
    for (const BatchSequence& q : sequences) {
      runtime::NewtonCoreChoice made = runtime::make_newton_core(*q.setup, runtime::Backend::Cuda, cuda);
      REQUIRE(made.boundary);
      Interpolator I(*q.setup, q.key_times, q.keyframes, q.options, std::move(made.core), std::move(made.boundary));
      reference.push_back(I.sequence(q.times));
    }
  }
  for (int workers : {1, 4}) {
    INFO("workers = " << workers);
    o.workers = workers;
    const BatchResult r = solve_batch(sequences, o);
    for (const auto& q : r.sequences) CHECK(q.error == "");
    REQUIRE(r.failed() == 0);
    for (size_t s = 0; s < sequences.size(); ++s) {
      REQUIRE(r.sequences[s].frames.size() == reference[s].size());
      for (size_t i = 0; i < reference[s].size(); ++i) {
        CHECK(r.sequences[s].frames[i].certified);
        require_same(r.sequences[s].frames[i], reference[s][i]);
      }
    }
  }
}
