// Newton stress benchmark (issue #20): runs the stress corpus (bench/stress/corpus.json,
// made by bench/stress/make_corpus.py) with each Hessian projection at several frame
// counts per keyframe interval and prints, per shape, iterations per frame (mean, p99,
// max), frames at the iteration cap, certified and non-converged frames and time per
// frame; then the whole corpus, the cost per frame against the number of holes (grid
// shapes) and a summary line against the targets. Keyframes are authored from the
// sequences' handles and targets by solve_scene_keyframes (the authoring path), once per
// sequence (or read from --keyframes-cache, stress_cache.h); keyframes whose drag would
// fold (the closest certified map is kept) are counted. Authoring and runs (sequence x
// frames x projection) are spread over --jobs workers, each with its own Newton core;
// results are gathered by run, so the tables do not depend on the number of workers.
// Progress on stderr; --json FILE writes every number. Not a test.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <omp.h>
#include <set>
#include <sstream>
#include <thread>

#include "hsi/machine.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/runtime/backend.h"
#include "stress_cache.h"
#include "stress_corpus.h"

using namespace hsi;
using nlohmann::json;

namespace {

using Clock = std::chrono::steady_clock;
double s_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }


std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// A number in [0, 1], nan and trailing text refused (CLI::Range lets "nan" through: every
// comparison with it is false); `zero` says what 0 means, in the message.
CLI::Validator unit_interval(const std::string& zero) {
  return CLI::Validator(
      [zero](std::string& text) -> std::string {
        char* end = nullptr;
        const double r = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !(r >= 0 && r <= 1))
          return "expected a number in [0, 1] (" + zero + "), got '" + text + "'";
        return {};
      },
      "in [0, 1]");
}

HessianProjection projection_from(const std::string& s) {
  if (s == "delete") return HessianProjection::Delete;
  if (s == "fullproj") return HessianProjection::FullProj;
  if (s == "partproj") return HessianProjection::PartProj;
  throw CLI::ValidationError("--projections", "unknown projection '" + s + "' (delete, fullproj, partproj)");
}

// Frames of some runs, pooled (keyframes excluded: they are not solved).
struct Stats {
  std::vector<int> iterations;
  long at_cap = 0, certified = 0;
  double ms = 0;
  int runs = 0, failed_runs = 0;  // failed: the interpolator threw
  // The frames that stopped without converging: t, iterations, why (NewtonStop).
  struct Unconverged {
    double t = 0;
    int iterations = 0;
    NewtonStop stop = NewtonStop::IterationLimit;
  };
  std::vector<Unconverged> unconverged;

  void add(const FrameResult& f, int max_iterations) {
    iterations.push_back(f.iterations);
    if (!f.converged) unconverged.push_back({f.t, f.iterations, f.stop});
    at_cap += f.iterations >= max_iterations || !f.converged;
    certified += f.certified;
    ms += f.ms;
  }
  void add(const Stats& o) {
    iterations.insert(iterations.end(), o.iterations.begin(), o.iterations.end());
    unconverged.insert(unconverged.end(), o.unconverged.begin(), o.unconverged.end());
    at_cap += o.at_cap;
    certified += o.certified;
    ms += o.ms;
    runs += o.runs;
    failed_runs += o.failed_runs;
  }
  long frames() const { return static_cast<long>(iterations.size()); }
  long not_converged() const { return static_cast<long>(unconverged.size()); }
  double mean() const {
    if (iterations.empty()) return NAN;
    double s = 0;
    for (int i : iterations) s += i;
    return s / static_cast<double>(iterations.size());
  }
  int quantile(double q) const {
    if (iterations.empty()) return 0;
    std::vector<int> v = iterations;
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1);
    std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
    return v[k];
  }
  int max() const { return iterations.empty() ? 0 : *std::max_element(iterations.begin(), iterations.end()); }
  double ms_per_frame() const { return iterations.empty() ? NAN : ms / static_cast<double>(iterations.size()); }
  // "t=0.700 stagnated after 46 it, ..." (empty when every frame converged).
  std::string unconverged_text() const {
    std::string out;
    char buf[96];
    for (const Unconverged& u : unconverged) {
      std::snprintf(buf, sizeof buf, "%st=%.4f %s after %d it", out.empty() ? "" : ", ", u.t, to_string(u.stop), u.iterations);
      out += buf;
    }
    return out;
  }
  json to_json() const {
    json u = json::array();
    for (const Unconverged& x : unconverged) u.push_back({{"t", x.t}, {"iterations", x.iterations}, {"stop", to_string(x.stop)}});
    return {{"runs", runs},          {"failed_runs", failed_runs},       {"frames", frames()},
            {"mean_iterations", iterations.empty() ? json(nullptr) : json(mean())},
            {"p99_iterations", quantile(0.99)}, {"max_iterations", max()}, {"at_cap", at_cap},
            {"certified", certified},           {"not_converged", not_converged()},
            {"ms_per_frame", iterations.empty() ? json(nullptr) : json(ms_per_frame())},
            {"unconverged_frames", u}};
  }
};

using RunKey = std::pair<int, HessianProjection>;  // frames per interval (kMid: cold midpoints), projection

// --frames mid: each keyframe interval's midpoint solved cold from the interval's first
// keyframe (no warm start), the setting of the paper's Table 1 (t = 0.5 from keyframe 0),
// where the projection decides how Newton gets from far away.
constexpr int kMid = 0;
std::string frames_label(int F) { return F == kMid ? "mid" : std::to_string(F); }
json frames_json(int F) { return F == kMid ? json("mid") : json(F); }

void print_header() {
  std::printf("| frames/interval | projection | runs | frames | mean it | p99 it | max it | at cap | certified | "
              "not converged | ms/frame |\n|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}
void print_row(const RunKey& k, const Stats& s) {
  std::printf("| %s | %s | %d%s | %ld | %.2f | %d | %d | %ld | %ld | %ld | %.1f |\n", frames_label(k.first).c_str(), to_string(k.second), s.runs,
              s.failed_runs ? (" (" + std::to_string(s.failed_runs) + " failed)").c_str() : "", s.frames(), s.mean(),
              s.quantile(0.99), s.max(), s.at_cap, s.certified, s.not_converged(), s.ms_per_frame());
}

// The frames of a run solved as Interpolator::sequence solves them (the blended metric,
// newton_solve warm-started from the previous frame, chord steps from the last exact
// system when the options have them), each Newton iteration printed.
void trace_run(Interpolator& interp, const ShapeSetup& setup, const std::vector<double>& key_times, int frames,
               const std::string& what) {
  NewtonOptions no = frame_newton_options(interp.options());
  KeptSystem kept;
  if (interp.options().chord_steps) no.kept_system = &kept;
  SecantPredictor predictor;  // InterpolationOptions::predict_start, as Interpolator::sequence
  int last_iterations = 0;
  const std::vector<double> times = sequence_times({interp.t_begin(), interp.t_end()}, frames);
  Eigen::VectorXd x;
  std::string out = "trace " + what + "\n";
  char b[300];
  const auto print = [&](const NewtonResult& r, double t, const char* start) {
    std::snprintf(b, sizeof b, "  t %.4f: %d it, %s%s\n", t, r.iterations, r.message.c_str(), start);
    out += b;
    for (const NewtonIteration& k : r.log) {
      std::snprintf(b, sizeof b, "    E %.12f step %.3g %s%s %s dec2 %.3g |g| %.3g smax %.3g bt %d rej %d\n", k.energy, k.step, k.chord ? "chord " : "",
                    k.shifted ? "shift" : k.exact_hessian ? "exact" : to_string(k.projection), k.all_samples ? "G" : "H", k.decrement2, k.gradient_norm, k.max_safe_step, k.backtracks,
                    k.certificate_rejections);
      out += b;
    }
  };
  for (size_t i = 0; i < times.size(); ++i) {
    if (std::count(key_times.begin(), key_times.end(), times[i])) {  // a keyframe: the frame is the keyframe itself
      x = interp.frame(times[i]).x;
      predictor.add(times[i], x);
      kept = KeptSystem{};  // as Interpolator::sequence: nothing carried across a keyframe…
      last_iterations = 0;
      if (no.kept_system && interp.options().seed_chord_at_keyframes && i + 1 < times.size()) {
        interp.core().set_targets(interp.blended_metric(times[i]));  // … but the keyframe's own exact system
        newton_seed_kept_system(interp.core(), setup.metric_space, x, no, kept);
      }
      continue;
    }
    interp.core().set_targets(interp.blended_metric(times[i]));
    const auto hi = std::upper_bound(key_times.begin(), key_times.end(), times[i]);
    const Eigen::VectorXd p = predicts_start(interp.options().predict_start, last_iterations)
                                  ? predictor.predict(times[i], *(hi - 1), *hi)
                                  : Eigen::VectorXd();
    NewtonResult r;
    if (p.size()) {
      NewtonOptions np = no;
      np.chord_from_start = false;
      r = newton_solve(interp.core(), setup.metric_space, &setup.certifier, nullptr, p, np);
      print(r, times[i], " (from the secant's start)");
    }
    if (!p.size() || !(r.certified && r.converged)) {
      const int before = p.size() ? r.iterations : 0;
      r = newton_solve(interp.core(), setup.metric_space, &setup.certifier, nullptr, x, no);
      print(r, times[i], p.size() ? " (again, from the previous frame)" : "");
      r.iterations += before;
    }
    last_iterations = r.iterations;
    if (r.certified) x = r.x;
    if (r.certified && r.converged)
      predictor.add(times[i], x);
    else
      predictor.clear();
  }
  std::fputs(out.c_str(), stderr);
}

// The benchmark's worker pool: tasks 0..count-1 (in the given order) on `workers`
// threads, each thread running its OpenMP regions on `omp_threads` threads. A task is
// started only while keep_going() says so. Deliberately small and local: the engine's
// batch solver (branch batch) can take its place.
void run_pool(const std::vector<int>& order, int workers, int omp_threads, const std::function<bool()>& keep_going,
              const std::function<void(int task)>& fn) {
  std::atomic<size_t> next{0};
  auto work = [&] {
    omp_set_num_threads(omp_threads);  // this thread's OpenMP teams
    for (size_t i = next++; i < order.size(); i = next++) {
      if (!keep_going()) continue;
      fn(order[i]);
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < std::min<int>(workers, static_cast<int>(order.size())); ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi Newton stress benchmark: runs the stress corpus (bench/stress/) and prints Markdown tables"};
  std::string corpus_file = HSI_STRESS_DIR "/corpus.json", shapes_opt, families_opt, kinds_opt, ids_opt;
  std::string frames_opt = "60,100,500", projections_opt = "delete,fullproj,partproj", backend = "cpu", json_file, export_dir;
  std::string cache_file;
  int limit = 0, samples = 0, max_iterations = 100, jobs = 1, threads = 0;
  bool paper_newton = false, author_only = false, trace = false, reverse_loops = false, no_chord = false, no_checked_stop = false,
       no_carry = false, seed_chord = InterpolationOptions{}.seed_chord_at_keyframes;
  std::string predict_start = to_string(InterpolationOptions{}.predict_start);
  double hessian_ratio = 0;
  std::string exact_samples = to_string(InterpolationOptions{}.exact_samples);
  double time_limit = 0, projected_decrement_stop = InterpolationOptions{}.projected_decrement_stop,
         chord_decrement_stop = InterpolationOptions{}.chord_decrement_stop;
  app.add_option("--corpus", corpus_file, "The corpus file")->capture_default_str();
  app.add_option("--shapes", shapes_opt, "Only these shapes (comma-separated names)");
  app.add_option("--families", families_opt, "Only shapes of these families: bundled, thin, grid, sprite");
  app.add_option("--kinds", kinds_opt, "Only sequences of these kinds (hinge, bend_steps, ...)");
  app.add_option("--sequences", ids_opt, "Only these sequences (comma-separated ids, shape/kind)");
  app.add_option("--limit", limit, "At most this many sequences per shape (0: all)")->capture_default_str();
  app.add_option("--frames", frames_opt,
                 "Frames per keyframe interval (comma-separated); 'mid': each interval's midpoint solved cold from its "
                 "first keyframe, the setting of the paper's Table 1")->capture_default_str();
  app.add_option("--projections", projections_opt, "Hessian projections (comma-separated)")->capture_default_str();
  app.add_option("--samples", samples, "|G| for every sequence (0: each sequence's own, 2,000 to 40,000)")->capture_default_str();
  app.add_option("--max-iterations", max_iterations, "Newton iteration cap per frame")->capture_default_str();
  app.add_option("--hessian-ratio", hessian_ratio,
                 "The Hessian's share r of the samples G in the runs (0: each scene's own, default 0.2); authoring keeps the "
                 "scene's")
      ->check(unit_interval("0: each scene's own ratio"));
  app.add_option("--exact-samples", exact_samples,
                 "The samples the exact Newton systems' Hessians sum over in the runs (InterpolationOptions::exact_samples): "
                 "subset (H), subset-then-all (H, then all of G where H's is not positive definite), all (G), auto (the core's "
                 "choice: subset on the CPU, all on CUDA)")
      ->capture_default_str()
      ->check(CLI::IsMember(exact_samples_names()));
  app.add_option("--projected-decrement-stop", projected_decrement_stop,
                 "Converged also when a projected system's decrement is below this fraction of the tolerance "
                 "(InterpolationOptions::projected_decrement_stop; 0: never)")
      ->capture_default_str()
      ->check(unit_interval("0: never"));
  app.add_flag("--no-checked-decrement-stop", no_checked_stop,
               "Without the checked decrement stop (InterpolationOptions::checked_decrement_stop off): a projected "
               "decrement below the tolerance, scaled by the previous full step's model error, does not end a frame");
  app.add_option("--chord-decrement-stop", chord_decrement_stop,
                 "Converged also when, after a full chord step, the kept system's decrement (scaled by that step's model "
                 "error) is below this fraction of the tolerance (InterpolationOptions::chord_decrement_stop; 0: never)")
      ->capture_default_str()
      ->check(unit_interval("0: never"));
  app.add_flag("--seed-chord,!--no-seed-chord", seed_chord,
               "Seed the chord slot at each keyframe with the keyframe's own exact system, so that the first frame of an "
               "interval starts with a chord step (InterpolationOptions::seed_chord_at_keyframes)")
      ->capture_default_str();
  app.add_flag("--no-carry-all-samples", no_carry,
               "A frame's move of its Hessians to all of G is not carried to the next frames "
               "(InterpolationOptions::carry_all_samples off; by default on the CUDA core)");
  app.add_flag("--no-chord", no_chord,
               "Sequences without chord steps (InterpolationOptions::chord_steps off): every frame's Newton systems built "
               "and factored at its own points, as before the chord steps");
  app.add_option("--predict-start", predict_start,
                 "Where frames start (InterpolationOptions::predict_start): off (the previous frame), always (the "
                 "secant through the last two), auto (the secant after a frame of more than one iteration)")
      ->capture_default_str()
      ->check(CLI::IsMember(predict_start_names()));
  app.add_flag("--paper-newton", paper_newton,
               "The paper's plain projected Newton (rotation gauged, no exact Hessian): the reference the fix is measured against");
  app.add_option("--backend", backend, runtime::kBackendHelp)
      ->capture_default_str()
      ->check(CLI::IsMember(runtime::backend_names()));
  app.add_option("--jobs", jobs,
                 "Workers: sequences are authored and runs (sequence x frames x projection) solved on this many threads, "
                 "each with its own Newton core (CUDA cores own their streams, so they run concurrently on one GPU)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--threads", threads,
                 "OpenMP threads per worker (0: the OpenMP threads / jobs, at least 1); on the CPU backend the round-off "
                 "of the sums over samples depends on it, the order and set of results never")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  app.add_option("--keyframes-cache", cache_file,
                 "Read authored keyframes from this file where their inputs are unchanged, author the others and write "
                 "them back (created if absent)");
  app.add_flag("--author-only", author_only, "Author the selection's keyframes (filling --keyframes-cache) and stop");
  app.add_option("--time-limit", time_limit,
                 "Start no new authoring or run after this many seconds (0: none); the output then says PARTIAL and "
                 "covers what ran")
      ->capture_default_str();
  app.add_flag("--trace", trace,
               "Print every frame's Newton iterations (energy, step, exact or projected system, decrement, backtracks, "
               "certificate rejections) to stderr, solving the frames as the interpolator does (warm-started); with "
               "--jobs 1 for readable output");
  app.add_flag("--reverse-loops", reverse_loops,
               "Read every loop of each shape the other way round (the same shapes in the other orientation); the "
               "keyframes are authored anew (their cache key is the reversed text): use a separate --keyframes-cache");
  app.add_option("--json", json_file, "Also write every number to this JSON file");
  app.add_option("--export", export_dir, "Write the selected sequences as scene files (handles + targets) into this folder and stop");
  CLI11_PARSE(app, argc, argv);
  // The chord decrement stop the runs use: none without chord steps or in the paper's plain Newton.
  const double chord_stop = no_chord || paper_newton ? 0.0 : chord_decrement_stop;

  std::vector<int> frame_counts;
  std::vector<HessianProjection> projections;
  try {
    for (const std::string& f : split(frames_opt)) {
      if (f == "mid") {
        frame_counts.push_back(kMid);
        continue;
      }
      std::size_t used = 0;
      int F = 0;
      try {
        F = std::stoi(f, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != f.size() || F < 1) throw std::invalid_argument("--frames: '" + f + "' is not a frame count >= 1 or 'mid'");
      frame_counts.push_back(F);
    }
    for (const std::string& p : split(projections_opt)) projections.push_back(projection_from(p));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_stress: %s\n", e.what());
    return 2;
  }
  if (author_only && cache_file.empty()) {
    std::fprintf(stderr, "bench_stress: --author-only needs --keyframes-cache FILE to keep what it authors\n");
    return 2;
  }
  const stress::Corpus corpus = stress::load_corpus(corpus_file);
  const auto shape_set = split(shapes_opt), family_set = split(families_opt), kind_set = split(kinds_opt), id_set = split(ids_opt);
  auto wanted = [](const std::vector<std::string>& set, const std::string& v) {
    return set.empty() || std::find(set.begin(), set.end(), v) != set.end();
  };
  for (const std::string& s : shape_set) (void)corpus.shape(s);  // unknown names are refused

  // The selection, grouped by shape in corpus order.
  std::vector<std::pair<const stress::ShapeEntry*, std::vector<const stress::Sequence*>>> plan;
  int total_sequences = 0;
  for (const stress::ShapeEntry& sh : corpus.shapes) {
    if (!wanted(shape_set, sh.name) || !wanted(family_set, sh.family)) continue;
    std::vector<const stress::Sequence*> seqs;
    for (const stress::Sequence& q : corpus.sequences)
      if (q.shape == sh.name && wanted(kind_set, q.kind) && wanted(id_set, q.id) && (limit <= 0 || static_cast<int>(seqs.size()) < limit))
        seqs.push_back(&q);
    if (seqs.empty()) continue;
    total_sequences += static_cast<int>(seqs.size());
    plan.emplace_back(&sh, std::move(seqs));
  }
  if (plan.empty()) {
    std::fprintf(stderr, "bench_stress: no sequence selected\n");
    return 2;
  }

  if (!export_dir.empty()) {
    std::filesystem::create_directories(export_dir);
    for (const auto& [sh, seqs] : plan) {
      const Scene shape = stress::load_shape(corpus, *sh, reverse_loops);
      for (const stress::Sequence* q : seqs) {
        Scene scene = stress::sequence_scene(shape, *q, samples);
        if (!scene.texture.empty()) scene.texture = std::filesystem::absolute(scene.texture_path());
        std::string file = q->id;
        std::replace(file.begin(), file.end(), '/', '.');
        save_scene(scene, std::filesystem::path(export_dir) / (file + ".json"));
      }
    }
    std::printf("wrote %d scene files into %s\n", total_sequences, export_dir.c_str());
    return 0;
  }

  const int omp_threads = threads > 0 ? threads : std::max(1, omp_get_max_threads() / jobs);
  const Machine machine = this_machine();
  std::printf("# hsi Newton stress benchmark\n\n");
  std::printf("Machine: %s, %d logical cores; backend %s; %d workers x %d OpenMP threads\n", machine.cpu.c_str(), machine.cores,
              backend.c_str(), jobs, omp_threads);
  std::printf("Corpus: %s (seed %d): %d of %zu sequences on %zu shapes; |G| %s; frames per interval %s; projections %s; "
              "iteration cap %d; exact systems over %s; projected-decrement stop %g; chord-decrement stop %g%s%s%s%s%s%s\n\n",
              corpus_file.c_str(), corpus.seed, total_sequences, corpus.sequences.size(), plan.size(),
              samples > 0 ? std::to_string(samples).c_str() : "per sequence", frames_opt.c_str(), projections_opt.c_str(),
              max_iterations, exact_samples.c_str(), projected_decrement_stop, chord_stop, paper_newton ? "; the paper's plain Newton (--paper-newton)" : "",
              no_chord && !paper_newton ? "; no chord steps (--no-chord)" : "",
              no_checked_stop && !paper_newton ? "; no checked decrement stop (--no-checked-decrement-stop)" : "",
              no_carry && !paper_newton ? "; no carry of all samples (--no-carry-all-samples)" : "",
              paper_newton ? "" : ("; start prediction " + predict_start).c_str(),
              reverse_loops ? "; every shape's loops reversed (--reverse-loops)" : "");
  std::printf("Per run: F frames per keyframe interval, F x (keyframes - 1) + 1 frames in all, warm-started; the\n"
              "keyframes themselves are not counted. at cap: iterations >= cap or not converged. it: Newton\n"
              "iterations per frame. ms/frame: the solve (Newton + certificate) per frame. F = mid: each\n"
              "interval's midpoint solved cold from its first keyframe (the paper's Table 1), one frame per interval.\n");
  std::fflush(stdout);
  const auto t_start = Clock::now();
  auto in_time = [&] { return !(time_limit > 0 && s_since(t_start) > time_limit); };

  // Shapes and setups (one per shape and |G|), made once on first use by any worker.
  struct ShapeSlot {
    std::once_flag once;
    Scene scene;
    std::string contents, error;  // the scene file's bytes (the cache key), why it could not be loaded
  };
  struct SetupSlot {
    std::once_flag once;
    std::unique_ptr<ShapeSetup> setup;
    std::string error;
  };
  std::vector<ShapeSlot> shape_slots(plan.size());
  std::map<std::tuple<size_t, int, bool>, SetupSlot> setup_slots;  // (shape, |G|, for the runs)
  // One item per sequence, in plan order.
  struct Item {
    size_t shape = 0;
    const stress::Sequence* q = nullptr;
    int samples = 0;
    uint64_t hash = 0;
    bool cached = false, stale = false, authored = false;  // authored: keyframes in hand (from the cache or made now)
    std::string uncertified;  // a cached keyframe today's certificate does not certify: why (authored again)
    int n = 0;
    std::string error;  // authoring failed
    stress::Authored a;
  };
  std::vector<Item> items;
  for (size_t s = 0; s < plan.size(); ++s) {
    try {
      shape_slots[s].contents = stress::shape_file_text(corpus, *plan[s].first, reverse_loops);
    } catch (const std::exception& e) {
      shape_slots[s].error = e.what();
    }
    for (const stress::Sequence* q : plan[s].second) {
      Item it;
      it.shape = s;
      it.q = q;
      it.samples = samples > 0 ? samples : q->samples;
      it.hash = stress::keyframes_hash(shape_slots[s].contents, *q, it.samples);
      (void)setup_slots[{s, it.samples, false}];
      (void)setup_slots[{s, it.samples, true}];
      items.push_back(std::move(it));
    }
  }
  auto shape_of = [&](size_t s) -> const Scene& {
    ShapeSlot& slot = shape_slots[s];
    std::call_once(slot.once, [&] {
      if (!slot.error.empty()) return;
      try {
        slot.scene = stress::shape_scene(corpus, *plan[s].first, slot.contents);
      } catch (const std::exception& e) {
        slot.error = std::string("cannot load the shape: ") + e.what();
      }
    });
    if (!slot.error.empty()) throw std::runtime_error(slot.error);
    return slot.scene;
  };
  // Authoring always uses the scene's Hessian ratio (the cache's keyframes do not depend
  // on --hessian-ratio); the runs use --hessian-ratio where given (the same setup otherwise).
  auto setup_of = [&](const Item& it, bool for_runs) -> const ShapeSetup& {
    SetupSlot& slot = setup_slots.at({it.shape, it.samples, for_runs && hessian_ratio > 0});
    std::call_once(slot.once, [&] {
      try {
        const Scene scene = stress::sequence_scene(shape_of(it.shape), *it.q, it.samples);
        slot.setup = make_shape_setup(scene, scene.samples, for_runs ? hessian_ratio : 0.0);
      } catch (const std::exception& e) {
        slot.error = e.what();
      }
    });
    if (!slot.setup) throw std::runtime_error(slot.error);
    return *slot.setup;
  };

  // 1. Keyframes: from the cache where the key matches, else authored (in parallel over
  //    sequences, the costliest first; the cache is saved every few seconds and at the end).
  stress::KeyframeCache cache;
  if (!cache_file.empty()) {
    try {
      cache.load(cache_file);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_stress: %s\n", e.what());
      return 2;
    }
  }
  std::vector<int> to_author;
  for (size_t i = 0; i < items.size(); ++i) {
    Item& it = items[i];
    if (const stress::CacheEntry* c = cache.find(it.q->id, it.samples, it.hash)) {
      it.a = stress::from_entry(*c);
      it.cached = it.authored = true;
    } else {
      it.stale = cache.has_stale(it.q->id, it.samples, it.hash);
      to_author.push_back(static_cast<int>(i));
    }
  }
  // The cache key does not cover the solver's code: a cached keyframe that today's
  // certificate cannot certify (one authored before the certificate counted its own
  // rounding, at a margin within round-off), or whose coefficients in the interpolation's
  // reduced space it cannot (one authored at the fold limit before authoring kept a
  // margin), is authored again, not run and failed.
  {
    std::vector<int> cached_items;
    for (size_t i = 0; i < items.size(); ++i)
      if (items[i].cached) cached_items.push_back(static_cast<int>(i));
    std::mutex verify_mutex;
    run_pool(cached_items, jobs, omp_threads, [] { return true; }, [&](int i) {
      Item& it = items[static_cast<size_t>(i)];
      try {
        it.uncertified = stress::uncertified_keyframe(setup_of(it, false), it.a);
      } catch (const std::exception& e) {
        it.uncertified = e.what();
      }
      if (it.uncertified.empty()) return;
      it.cached = it.authored = false;
      it.stale = true;
      const std::lock_guard<std::mutex> lock(verify_mutex);
      std::fprintf(stderr, "[cache] %s: cached keyframes not certified now (%s): authored again\n", it.q->id.c_str(), it.uncertified.c_str());
      to_author.push_back(i);
    });
  }
  std::stable_sort(to_author.begin(), to_author.end(), [&](int x, int y) {
    auto cost = [&](int i) { return static_cast<double>(items[static_cast<size_t>(i)].samples) * static_cast<double>(items[static_cast<size_t>(i)].q->targets.size()); };
    return cost(x) > cost(y);
  });
  std::mutex mutex;  // the cache, progress lines, the core's name
  std::atomic<int> authored_count{0};
  auto last_save = Clock::now();
  bool cache_dirty = false;
  const auto t_author = Clock::now();
  // Authoring runs on --backend's core too (the drag's solves are the same loop; the
  // maps agree with the CPU core's to round-off, and the cache key does not say which).
  const runtime::CudaStatus cuda = runtime::cuda_status();
  KeyframeOptions authoring;
  authoring.make_core = [&](const ShapeSetup& s) {
    return std::move(runtime::make_newton_core(s, runtime::parse_backend(backend), cuda, false).core);
  };
  run_pool(to_author, jobs, omp_threads, in_time, [&](int i) {
    Item& it = items[static_cast<size_t>(i)];
    const auto t0 = Clock::now();
    try {
      const ShapeSetup& setup = setup_of(it, false);
      Scene scene = stress::sequence_scene(shape_of(it.shape), *it.q, it.samples);
      it.a = stress::author(scene, setup, authoring);
      it.authored = true;
    } catch (const std::exception& e) {
      it.error = e.what();
    }
    const std::lock_guard<std::mutex> lock(mutex);
    const int k = ++authored_count;
    if (!it.error.empty()) {
      std::fprintf(stderr, "[author %d/%zu] %s: authoring failed: %s\n", k, to_author.size(), it.q->id.c_str(), it.error.c_str());
      return;
    }
    std::fprintf(stderr, "[author %d/%zu] %s (|G| %d, %zu keyframes%s): authored in %.1f s\n", k, to_author.size(), it.q->id.c_str(),
                 it.samples, it.a.maps.size(), it.a.unreached ? (", " + std::to_string(it.a.unreached) + " unreached: fold").c_str() : "",
                 s_since(t0));
    if (!cache_file.empty()) {
      cache.put(stress::to_entry(it.q->id, it.samples, it.hash, it.a));
      cache_dirty = true;
      if (s_since(last_save) > 10) {
        cache.save(cache_file);
        last_save = Clock::now();
        cache_dirty = false;
      }
    }
  });
  if (cache_dirty) cache.save(cache_file);
  int n_cached = 0, n_stale = 0, n_authored = 0, n_author_failed = 0, n_not_authored = 0;
  for (const Item& it : items) {
    n_cached += it.cached;
    n_stale += it.stale;
    n_authored += it.authored && !it.cached;
    n_author_failed += !it.error.empty();
    n_not_authored += !it.authored && it.error.empty();  // --time-limit
  }
  std::printf("\nKeyframes: %d sequences from the cache%s, %d authored now (%d of them stale in the cache) in %.0f s on %d workers, "
              "%d could not be authored%s\n",
              n_cached, cache_file.empty() ? " (none given)" : (" " + cache_file).c_str(), n_authored, n_stale, s_since(t_author),
              jobs, n_author_failed,
              n_not_authored ? (", PARTIAL: " + std::to_string(n_not_authored) + " not authored (--time-limit)").c_str() : "");
  if (author_only) {
    if (!cache_file.empty()) std::printf("Cache %s: %zu entries, %ju bytes\n", cache_file.c_str(), cache.size(),
                                         static_cast<uintmax_t>(std::filesystem::file_size(cache_file)));
    return n_not_authored ? 3 : 0;
  }

  // 2. The runs: sequence x frames x projection, each on a worker with its own core;
  //    the costliest first, results kept by run index.
  struct Run {
    size_t item = 0;
    int F = 0;
    HessianProjection p = HessianProjection::PartProj;
    bool ran = false;
    Stats s;
    std::string error;
    double seconds = 0;
  };
  std::vector<Run> runs;
  for (size_t i = 0; i < items.size(); ++i)
    if (items[i].authored)
      for (int F : frame_counts)
        for (HessianProjection p : projections) runs.push_back({i, F, p, false, {}, {}, 0});
  std::vector<int> run_order(runs.size());
  for (size_t r = 0; r < runs.size(); ++r) run_order[r] = static_cast<int>(r);
  auto run_cost = [&](int r) {
    const Run& x = runs[static_cast<size_t>(r)];
    const Item& it = items[x.item];
    return static_cast<double>(x.F == kMid ? 10 : x.F) * static_cast<double>(it.a.times.size() - 1) * (2000.0 + it.samples);
  };
  std::stable_sort(run_order.begin(), run_order.end(), [&](int x, int y) { return run_cost(x) > run_cost(y); });
  std::string core_name, core_description;
  std::atomic<int> runs_done{0};
  run_pool(run_order, jobs, omp_threads, in_time, [&](int r) {
    Run& run = runs[static_cast<size_t>(r)];
    Item& it = items[run.item];
    const auto t1 = Clock::now();
    run.ran = true;
    run.s.runs = 1;
    try {
      const ShapeSetup& setup = setup_of(it, true);
      InterpolationOptions o;
      o.exact_hessian_when_definite = o.free_rotation = !paper_newton;
      if (paper_newton) o.escalate_after_iterations = 0;  // the paper's projection throughout
      o.chord_steps = !no_chord && !paper_newton;
      o.predict_start = paper_newton ? PredictStart::Off : parse_predict_start(predict_start);
      o.exact_samples = parse_exact_samples(exact_samples);
      o.projected_decrement_stop = projected_decrement_stop;
      o.checked_decrement_stop = !no_checked_stop && !paper_newton;
      o.chord_decrement_stop = chord_stop;
      o.seed_chord_at_keyframes = seed_chord;
      if (no_carry || paper_newton) o.carry_all_samples = AllSamplesCarry::Off;
      o.projection = run.p;
      o.max_iterations = max_iterations;
      runtime::NewtonCoreChoice core = runtime::make_newton_core(setup, runtime::parse_backend(backend), cuda);
      {
        const std::lock_guard<std::mutex> lock(mutex);
        it.n = setup.map_space.n();
        if (core_name.empty()) {
          core_name = core.core->name();
          core_description = runtime::describe(core.choice);
        }
      }
      Interpolator interp(setup, it.a.times, it.a.maps, o, std::move(core.core));
      const int intervals = static_cast<int>(it.a.times.size()) - 1;
      if (run.F == kMid) {
        for (int k = 0; k < intervals; ++k) {
          const FrameResult f = interp.frame((it.a.times[static_cast<size_t>(k)] + it.a.times[static_cast<size_t>(k) + 1]) / 2);
          if (!f.keyframe && !f.held) run.s.add(f, max_iterations);
        }
      } else {
        if (trace) trace_run(interp, setup, it.a.times, run.F * intervals + 1, it.q->id + " F=" + std::to_string(run.F) + " " + to_string(run.p));
        for (const FrameResult& f : interp.sequence(run.F * intervals + 1))
          if (!f.keyframe) run.s.add(f, max_iterations);
      }
    } catch (const std::exception& e) {
      run.error = e.what();
      run.s.failed_runs = 1;
    }
    run.seconds = s_since(t1);
    const std::lock_guard<std::mutex> lock(mutex);
    const int k = ++runs_done;
    if (!run.error.empty())
      std::fprintf(stderr, "[run %d/%zu] %s F=%s %s: failed: %s\n", k, runs.size(), it.q->id.c_str(), frames_label(run.F).c_str(), to_string(run.p),
                   run.error.c_str());
    else
      std::fprintf(stderr, "[run %d/%zu] %s F=%s %-8s %4ld frames: mean %.2f it, max %d, at cap %ld, uncertified %ld  (%.1f s)%s%s\n", k,
                   runs.size(), it.q->id.c_str(), frames_label(run.F).c_str(), to_string(run.p), run.s.frames(), run.s.mean(), run.s.max(),
                   run.s.at_cap, run.s.frames() - run.s.certified, run.seconds, run.s.unconverged.empty() ? "" : "; not converged: ",
                   run.s.unconverged_text().c_str());
  });
  if (!core_description.empty()) std::printf("Newton core: %s\n", core_description.c_str());

  // 3. Tables, in plan order: the same whatever the number of workers.
  json out;
  out["machine"] = {{"cpu", machine.cpu}, {"cores", machine.cores}, {"workers", jobs}, {"omp_threads_per_worker", omp_threads},
                    {"backend", backend}};
  out["options"] = {{"corpus", corpus_file},     {"seed", corpus.seed},         {"samples", samples},
                    {"frames", frame_counts},    {"projections", split(projections_opt)}, {"max_iterations", max_iterations},
                    {"limit", limit},            {"paper_newton", paper_newton}, {"time_limit", time_limit},
                    {"hessian_ratio", hessian_ratio}, {"chord_steps", !no_chord && !paper_newton}, {"predict_start", paper_newton ? "off" : predict_start}, {"checked_decrement_stop", !no_checked_stop && !paper_newton}, {"chord_decrement_stop", chord_stop}, {"seed_chord_at_keyframes", seed_chord && !no_chord && !paper_newton}, {"carry_all_samples", no_carry || paper_newton ? "off" : "auto"}, {"exact_samples", exact_samples},
                    {"projected_decrement_stop", projected_decrement_stop}, {"reverse_loops", reverse_loops}};
  json runs_json = json::array(), shapes_json = json::array();
  std::map<RunKey, Stats> total;
  std::map<std::string, std::map<RunKey, Stats>> by_shape;
  struct GridRow {
    int holes = 0, n = 0;
    std::set<int> samples;
    std::map<RunKey, Stats> stats;
  };
  std::map<int, GridRow> grid_rows;  // by holes
  long keyframes_total = 0, keyframes_unreached = 0;
  int runs_not_run = 0, sequences_not_run = 0;
  for (const Run& r : runs) runs_not_run += !r.ran;
  const int runs_planned = static_cast<int>(runs.size()) + n_not_authored * static_cast<int>(frame_counts.size() * projections.size());
  runs_not_run += n_not_authored * static_cast<int>(frame_counts.size() * projections.size());
  size_t next_run = 0;
  for (size_t s = 0; s < plan.size(); ++s) {
    const stress::ShapeEntry* sh = plan[s].first;
    std::map<RunKey, Stats>& mine = by_shape[sh->name];
    long shape_keyframes = 0, shape_unreached = 0;
    int shape_failed = 0, shape_not_run = 0, holes = 0;
    try {
      holes = static_cast<int>(shape_of(s).shape.holes.size());
    } catch (const std::exception&) {  // counted below as sequences not authored
    }
    for (size_t i = 0; i < items.size(); ++i) {
      const Item& it = items[i];
      if (it.shape != s) continue;
      if (!it.error.empty()) {
        ++shape_failed;
        runs_json.push_back({{"id", it.q->id}, {"samples", it.samples}, {"authoring_error", it.error}});
        continue;
      }
      if (!it.authored) {
        shape_not_run += static_cast<int>(frame_counts.size() * projections.size());
        ++sequences_not_run;
        continue;
      }
      shape_keyframes += static_cast<long>(it.a.maps.size());
      shape_unreached += it.a.unreached;
      bool any_ran = false;
      for (; next_run < runs.size() && runs[next_run].item == i; ++next_run) {
        const Run& run = runs[next_run];
        if (!run.ran) {
          ++shape_not_run;
          continue;
        }
        any_ran = true;
        const RunKey key{run.F, run.p};
        json r = run.s.to_json();
        r["id"] = it.q->id;
        r["shape"] = it.q->shape;
        r["kind"] = it.q->kind;
        r["samples"] = it.samples;
        r["n"] = it.n;
        r["keyframes"] = it.a.maps.size();
        r["unreached_keyframes"] = it.a.unreached;
        r["max_target_error"] = it.a.max_target_error;
        r["keyframes_cached"] = it.cached;
        r["frames_per_interval"] = frames_json(run.F);
        r["projection"] = to_string(run.p);
        if (!run.error.empty()) r["error"] = run.error;
        runs_json.push_back(r);
        mine[key].add(run.s);
        total[key].add(run.s);
        if (sh->family == "grid") {
          GridRow& g = grid_rows[holes];
          g.holes = holes;
          g.n = it.n;
          g.samples.insert(it.samples);
          g.stats[key].add(run.s);
        }
      }
      if (!any_ran) ++sequences_not_run;
    }
    keyframes_total += shape_keyframes;
    keyframes_unreached += shape_unreached;
    if (mine.empty() && shape_failed == 0) continue;  // nothing ran (--time-limit)
    std::printf("\n## %s (%s, %d holes, %zu sequences; keyframes: %ld, %ld unreached (drag would fold)%s)%s\n\n", sh->name.c_str(),
                sh->family.c_str(), holes, plan[s].second.size(), shape_keyframes, shape_unreached,
                shape_failed ? (", " + std::to_string(shape_failed) + " sequences not authored").c_str() : "",
                shape_not_run ? (" PARTIAL: " + std::to_string(shape_not_run) + " runs not run (--time-limit)").c_str() : "");
    print_header();
    for (const auto& [k, st] : mine) print_row(k, st);
    std::fflush(stdout);
    json sj = {{"shape", sh->name},         {"family", sh->family},        {"holes", holes},
               {"sequences", plan[s].second.size()}, {"keyframes", shape_keyframes}, {"unreached_keyframes", shape_unreached},
               {"authoring_failed", shape_failed},   {"runs_not_run", shape_not_run}};
    json rows = json::array();
    for (const auto& [k, st] : mine) {
      json r = st.to_json();
      r["frames_per_interval"] = frames_json(k.first);
      r["projection"] = to_string(k.second);
      rows.push_back(r);
    }
    sj["rows"] = rows;
    shapes_json.push_back(sj);
  }

  const bool partial = runs_not_run > 0;
  std::string partial_note;
  if (partial) {
    char b[240];
    std::snprintf(b, sizeof b, "PARTIAL RUN (--time-limit %.0f s): %d of %d runs not run, %d of %d sequences not run", time_limit,
                  runs_not_run, runs_planned, sequences_not_run, total_sequences - n_author_failed);
    partial_note = b;
    std::printf("\n%s.\n", partial_note.c_str());
  }
  std::printf("\n## Whole selection (%d sequences, %ld keyframes, %ld unreached: drag would fold; %d sequences not authored)%s\n\n",
              total_sequences - sequences_not_run - n_author_failed, keyframes_total, keyframes_unreached, n_author_failed,
              partial ? " PARTIAL" : "");
  print_header();
  for (const auto& [k, s] : total) print_row(k, s);

  if (!grid_rows.empty()) {
    std::printf("\n## Cost per frame against the number of holes (grid shapes)%s\n\n", partial ? " PARTIAL" : "");
    std::printf("| holes | n | samples | frames/interval | projection | frames | mean it | ms/frame | ms/iteration |\n"
                "|---:|---:|---|---:|---|---:|---:|---:|---:|\n");
    for (const auto& [h, g] : grid_rows) {
      std::string gs;
      for (int v : g.samples) gs += (gs.empty() ? "" : ",") + std::to_string(v);
      for (const auto& [k, s] : g.stats)
        std::printf("| %d | %d | %s | %s | %s | %ld | %.2f | %.1f | %.2f |\n", h, g.n, gs.c_str(), frames_label(k.first).c_str(), to_string(k.second),
                    s.frames(), s.mean(), s.ms_per_frame(), s.iterations.empty() ? NAN : s.ms / std::max(1.0, s.mean() * static_cast<double>(s.frames())));
    }
  }

  // Targets (issue #20).
  long cap = 0;
  for (const auto& [k, s] : total) cap += s.at_cap;
  // PartProj against Delete per shape over the sequences both ran (the same as all of the
  // shape's runs unless --time-limit left some out: then a shape's two means would cover
  // different sequences).
  std::map<std::string, std::map<RunKey, Stats>> paired;
  {
    std::map<std::pair<size_t, int>, std::pair<const Run*, const Run*>> by_item;  // (item, F): PartProj's run, Delete's
    for (const Run& r : runs)
      if (r.ran) {
        auto& slot = by_item[{r.item, r.F}];
        if (r.p == HessianProjection::PartProj) slot.first = &r;
        if (r.p == HessianProjection::Delete) slot.second = &r;
      }
    for (const auto& [key, pd] : by_item)
      if (pd.first && pd.second) {
        auto& m = paired[plan[items[key.first].shape].first->name];
        m[{key.second, HessianProjection::PartProj}].add(pd.first->s);
        m[{key.second, HessianProjection::Delete}].add(pd.second->s);
      }
  }
  std::vector<std::string> worse;  // shapes where PartProj's mean exceeds Delete's at some frame count
  for (const auto& [shape, m] : paired)
    for (int F : frame_counts) {
      const auto pp = m.find({F, HessianProjection::PartProj}), de = m.find({F, HessianProjection::Delete});
      if (pp != m.end() && de != m.end() && pp->second.frames() && de->second.frames() && pp->second.mean() > de->second.mean())
        worse.push_back(shape + "@" + frames_label(F));
    }
  auto mean_at = [&](int F) {
    const auto it = total.find({F, HessianProjection::PartProj});
    return it == total.end() || !it->second.frames() ? NAN : it->second.mean();
  };
  const bool have_both = std::count(projections.begin(), projections.end(), HessianProjection::PartProj) &&
                         std::count(projections.begin(), projections.end(), HessianProjection::Delete);
  const double m100 = mean_at(100), m500 = mean_at(500);
  std::string summary = partial ? partial_note + ", targets judged on the runs that finished only: " : "";
  summary += "targets: frames at cap " + std::to_string(cap) + (cap == 0 ? " (ok)" : " (FAIL: want 0)");
  if (have_both) {
    std::string w;
    for (const std::string& s : worse) w += (w.empty() ? "" : ",") + s;
    summary += worse.empty() ? "; PartProj mean <= Delete on every shape (ok)" : "; PartProj mean > Delete on " + w + " (FAIL)";
  } else {
    summary += "; PartProj vs Delete: not measured";
  }
  char b[160];
  if (!std::isnan(m100)) {
    std::snprintf(b, sizeof b, "; PartProj mean at 100 frames/interval %.2f (%s: want <= 3.5)", m100, m100 <= 3.5 ? "ok" : "FAIL");
    summary += b;
  }
  if (!std::isnan(m500)) {
    std::snprintf(b, sizeof b, "; PartProj mean at 500 frames/interval %.2f (%s: want <= 2.5)", m500, m500 <= 2.5 ? "ok" : "FAIL");
    summary += b;
  }
  std::printf("\nNewton core: %s. Wall time %.0f s.\n\n%s\n", core_name.c_str(), s_since(t_start), summary.c_str());

  if (!json_file.empty()) {
    out["core"] = core_name;
    out["runs"] = runs_json;
    out["shapes"] = shapes_json;
    json tot = json::array();
    for (const auto& [k, s] : total) {
      json r = s.to_json();
      r["frames_per_interval"] = frames_json(k.first);
      r["projection"] = to_string(k.second);
      tot.push_back(r);
    }
    out["total"] = tot;
    out["partial"] = partial;
    out["runs_planned"] = runs_planned;
    out["runs_not_run"] = runs_not_run;
    out["sequences_run"] = total_sequences - sequences_not_run - n_author_failed;
    out["keyframes"] = {{"total", keyframes_total},
                        {"unreached", keyframes_unreached},
                        {"sequences_not_authored", n_author_failed},
                        {"sequences_from_cache", n_cached},
                        {"sequences_authored_now", n_authored},
                        {"stale_cache_entries", n_stale}};
    out["targets"] = {{"partial", partial},
                      {"at_cap", cap},
                      {"partproj_worse_than_delete", worse},
                      {"partproj_mean_100", std::isnan(m100) ? json(nullptr) : json(m100)},
                      {"partproj_mean_500", std::isnan(m500) ? json(nullptr) : json(m500)},
                      {"summary", summary}};
    std::ofstream f(json_file);
    f << out.dump(1) << "\n";
    if (!f) {
      std::fprintf(stderr, "bench_stress: cannot write %s\n", json_file.c_str());
      return 1;
    }
  }
  return 0;
}
