// Newton stress benchmark (issue #20): runs the stress corpus (bench/stress/corpus.json,
// made by bench/stress/make_corpus.py) with each Hessian projection at several frame
// counts per keyframe interval and prints, per shape, iterations per frame (mean, p99,
// max), frames at the iteration cap, certified and non-converged frames and time per
// frame; then the whole corpus, the cost per frame against the number of holes (grid
// shapes) and a summary line against the targets. Keyframes are authored from the
// sequences' handles and targets by solve_scene_keyframes (the authoring path), once per
// sequence; keyframes whose drag would fold (the closest certified map is kept) are
// counted. Progress on stderr; --json FILE writes every number. Not a test.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <omp.h>
#include <set>
#include <sstream>
#include <thread>

#include "hsi/machine.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/runtime/backend.h"
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

const char* projection_label(HessianProjection p) {
  switch (p) {
    case HessianProjection::Delete: return "delete";
    case HessianProjection::FullProj: return "fullproj";
    case HessianProjection::PartProj: return "partproj";
  }
  return "?";
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
  long at_cap = 0, certified = 0, not_converged = 0;
  double ms = 0;
  int runs = 0, failed_runs = 0;  // failed: the interpolator threw

  void add(const FrameResult& f, int max_iterations) {
    iterations.push_back(f.iterations);
    at_cap += f.iterations >= max_iterations || !f.converged;
    certified += f.certified;
    not_converged += !f.converged;
    ms += f.ms;
  }
  void add(const Stats& o) {
    iterations.insert(iterations.end(), o.iterations.begin(), o.iterations.end());
    at_cap += o.at_cap;
    certified += o.certified;
    not_converged += o.not_converged;
    ms += o.ms;
    runs += o.runs;
    failed_runs += o.failed_runs;
  }
  long frames() const { return static_cast<long>(iterations.size()); }
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
  json to_json() const {
    return {{"runs", runs},          {"failed_runs", failed_runs},       {"frames", frames()},
            {"mean_iterations", iterations.empty() ? json(nullptr) : json(mean())},
            {"p99_iterations", quantile(0.99)}, {"max_iterations", max()}, {"at_cap", at_cap},
            {"certified", certified},           {"not_converged", not_converged},
            {"ms_per_frame", iterations.empty() ? json(nullptr) : json(ms_per_frame())}};
  }
};

using RunKey = std::pair<int, HessianProjection>;  // frames per interval, projection

void print_header() {
  std::printf("| frames/interval | projection | runs | frames | mean it | p99 it | max it | at cap | certified | "
              "not converged | ms/frame |\n|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}
void print_row(const RunKey& k, const Stats& s) {
  std::printf("| %d | %s | %d%s | %ld | %.2f | %d | %d | %ld | %ld | %ld | %.1f |\n", k.first, projection_label(k.second), s.runs,
              s.failed_runs ? (" (" + std::to_string(s.failed_runs) + " failed)").c_str() : "", s.frames(), s.mean(),
              s.quantile(0.99), s.max(), s.at_cap, s.certified, s.not_converged, s.ms_per_frame());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi Newton stress benchmark: runs the stress corpus (bench/stress/) and prints Markdown tables"};
  std::string corpus_file = HSI_STRESS_DIR "/corpus.json", shapes_opt, families_opt, kinds_opt, ids_opt;
  std::string frames_opt = "60,100,500", projections_opt = "delete,fullproj,partproj", backend = "cpu", json_file, export_dir;
  int limit = 0, samples = 0, max_iterations = 100;
  bool paper_newton = false;
  double time_limit = 0;
  app.add_option("--corpus", corpus_file, "The corpus file")->capture_default_str();
  app.add_option("--shapes", shapes_opt, "Only these shapes (comma-separated names)");
  app.add_option("--families", families_opt, "Only shapes of these families: bundled, thin, grid, sprite");
  app.add_option("--kinds", kinds_opt, "Only sequences of these kinds (hinge, bend_steps, ...)");
  app.add_option("--sequences", ids_opt, "Only these sequences (comma-separated ids, shape/kind)");
  app.add_option("--limit", limit, "At most this many sequences per shape (0: all)")->capture_default_str();
  app.add_option("--frames", frames_opt, "Frames per keyframe interval (comma-separated)")->capture_default_str();
  app.add_option("--projections", projections_opt, "Hessian projections (comma-separated)")->capture_default_str();
  app.add_option("--samples", samples, "|G| for every sequence (0: each sequence's own, 2,000 to 40,000)")->capture_default_str();
  app.add_option("--max-iterations", max_iterations, "Newton iteration cap per frame")->capture_default_str();
  app.add_flag("--paper-newton", paper_newton,
               "The paper's plain projected Newton (rotation gauged, no exact Hessian): the reference the fix is measured against");
  app.add_option("--backend", backend, runtime::kBackendHelp)
      ->capture_default_str()
      ->check(CLI::IsMember(runtime::backend_names()));
  app.add_option("--time-limit", time_limit,
                 "Start no new sequence after this many seconds (0: none); the tables cover what ran")
      ->capture_default_str();
  app.add_option("--json", json_file, "Also write every number to this JSON file");
  app.add_option("--export", export_dir, "Write the selected sequences as scene files (handles + targets) into this folder and stop");
  CLI11_PARSE(app, argc, argv);

  std::vector<int> frame_counts;
  std::vector<HessianProjection> projections;
  try {
    for (const std::string& f : split(frames_opt)) frame_counts.push_back(std::stoi(f));
    for (const std::string& p : split(projections_opt)) projections.push_back(projection_from(p));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_stress: %s\n", e.what());
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
      const Scene shape = stress::load_shape(corpus, *sh);
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

  const Machine machine = this_machine();
  std::printf("# hsi Newton stress benchmark\n\n");
  std::printf("Machine: %s, %d logical cores, %d OpenMP threads; backend %s\n", machine.cpu.c_str(), machine.cores,
              omp_get_max_threads(), backend.c_str());
  std::printf("Corpus: %s (seed %d): %d of %zu sequences on %zu shapes; |G| %s; frames per interval %s; projections %s; "
              "iteration cap %d\n\n",
              corpus_file.c_str(), corpus.seed, total_sequences, corpus.sequences.size(), plan.size(),
              samples > 0 ? std::to_string(samples).c_str() : "per sequence", frames_opt.c_str(), projections_opt.c_str(),
              max_iterations);
  std::printf("Per run: F frames per keyframe interval, F x (keyframes - 1) + 1 frames in all, warm-started; the\n"
              "keyframes themselves are not counted. at cap: iterations >= cap or not converged. it: Newton\n"
              "iterations per frame. ms/frame: the solve (Newton + certificate) per frame.\n");
  std::fflush(stdout);

  json out;
  out["machine"] = {{"cpu", machine.cpu}, {"cores", machine.cores}, {"omp_threads", omp_get_max_threads()}, {"backend", backend}};
  out["options"] = {{"corpus", corpus_file}, {"seed", corpus.seed}, {"samples", samples}, {"frames", frame_counts},
                    {"projections", split(projections_opt)}, {"max_iterations", max_iterations}, {"limit", limit}};
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
  int authoring_failed = 0, done = 0, skipped = 0;
  std::string core_name;
  const auto t_start = Clock::now();

  for (const auto& [sh, seqs] : plan) {
    Scene shape;
    try {
      shape = stress::load_shape(corpus, *sh);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: cannot load the shape: %s\n", sh->name.c_str(), e.what());
      authoring_failed += static_cast<int>(seqs.size());
      done += static_cast<int>(seqs.size());
      continue;
    }
    const int holes = static_cast<int>(shape.shape.holes.size());
    std::map<int, std::unique_ptr<ShapeSetup>> setups;  // by |G|
    std::map<RunKey, Stats>& mine = by_shape[sh->name];
    long shape_keyframes = 0, shape_unreached = 0;
    int shape_failed = 0, n = 0;
    for (const stress::Sequence* q : seqs) {
      if (time_limit > 0 && s_since(t_start) > time_limit) {
        ++skipped;
        continue;
      }
      ++done;
      Scene scene = stress::sequence_scene(shape, *q, samples);
      auto& setup = setups[scene.samples];
      const auto t0 = Clock::now();
      stress::Authored a;
      try {
        if (!setup) setup = make_shape_setup(scene, scene.samples);
        n = setup->map_space.n();
        a = stress::author(scene, *setup);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "[%d/%d] %s: authoring failed: %s\n", done, total_sequences, q->id.c_str(), e.what());
        ++shape_failed;
        runs_json.push_back({{"id", q->id}, {"authoring_error", e.what()}});
        continue;
      }
      shape_keyframes += static_cast<long>(a.maps.size());
      shape_unreached += a.unreached;
      std::fprintf(stderr, "[%d/%d] %s (|G| %d, n %d, %zu keyframes%s): authored in %.1f s\n", done, total_sequences, q->id.c_str(),
                   scene.samples, n, a.maps.size(),
                   a.unreached ? (", " + std::to_string(a.unreached) + " unreached: fold").c_str() : "", s_since(t0));
      for (int F : frame_counts)
        for (HessianProjection p : projections) {
          const RunKey key{F, p};
          Stats s;
          s.runs = 1;
          const auto t1 = Clock::now();
          std::string error;
          try {
            InterpolationOptions o;
            o.exact_hessian_when_definite = o.free_rotation = !paper_newton;
            o.projection = p;
            o.max_iterations = max_iterations;
            runtime::NewtonCoreChoice core = runtime::make_newton_core(*setup, runtime::parse_backend(backend));
            if (core_name.empty()) {
              core_name = core.core->name();
              std::printf("Newton core: %s\n", runtime::describe(core.choice).c_str());
            }
            Interpolator interp(*setup, a.times, a.maps, o, std::move(core.core));
            const int intervals = static_cast<int>(a.times.size()) - 1;
            for (const FrameResult& f : interp.sequence(F * intervals + 1))
              if (!f.keyframe) s.add(f, max_iterations);
          } catch (const std::exception& e) {
            error = e.what();
            s.failed_runs = 1;
            std::fprintf(stderr, "    %s F=%d %s: failed: %s\n", q->id.c_str(), F, projection_label(p), e.what());
          }
          std::fprintf(stderr, "    F=%d %-8s %4ld frames: mean %.2f it, max %d, at cap %ld, uncertified %ld  (%.1f s)\n", F,
                       projection_label(p), s.frames(), s.mean(), s.max(), s.at_cap, s.frames() - s.certified, s_since(t1));
          json r = s.to_json();
          r["id"] = q->id;
          r["shape"] = q->shape;
          r["kind"] = q->kind;
          r["samples"] = scene.samples;
          r["n"] = n;
          r["keyframes"] = a.maps.size();
          r["unreached_keyframes"] = a.unreached;
          r["frames_per_interval"] = F;
          r["projection"] = projection_label(p);
          if (!error.empty()) r["error"] = error;
          runs_json.push_back(r);
          mine[key].add(s);
          total[key].add(s);
          if (sh->family == "grid") {
            GridRow& g = grid_rows[holes];
            g.holes = holes;
            g.n = n;
            g.samples.insert(scene.samples);
            g.stats[key].add(s);
          }
        }
    }
    if (mine.empty() && shape_failed == 0) continue;  // nothing ran (--time-limit)
    keyframes_total += shape_keyframes;
    keyframes_unreached += shape_unreached;
    authoring_failed += shape_failed;
    std::printf("\n## %s (%s, %d holes, %zu sequences; keyframes: %ld, %ld unreached (drag would fold)%s)\n\n", sh->name.c_str(),
                sh->family.c_str(), holes, seqs.size(), shape_keyframes, shape_unreached,
                shape_failed ? (", " + std::to_string(shape_failed) + " sequences not authored").c_str() : "");
    print_header();
    for (const auto& [k, s] : mine) print_row(k, s);
    std::fflush(stdout);
    json sj = {{"shape", sh->name}, {"family", sh->family}, {"holes", holes}, {"sequences", seqs.size()},
               {"keyframes", shape_keyframes}, {"unreached_keyframes", shape_unreached}, {"authoring_failed", shape_failed}};
    json rows = json::array();
    for (const auto& [k, s] : mine) {
      json r = s.to_json();
      r["frames_per_interval"] = k.first;
      r["projection"] = projection_label(k.second);
      rows.push_back(r);
    }
    sj["rows"] = rows;
    shapes_json.push_back(sj);
  }

  if (skipped) std::printf("\n--time-limit %.0f s reached: %d sequences not run.\n", time_limit, skipped);
  std::printf("\n## Whole selection (%d sequences, %ld keyframes, %ld unreached: drag would fold; %d sequences not authored)\n\n",
              total_sequences - skipped, keyframes_total, keyframes_unreached, authoring_failed);
  print_header();
  for (const auto& [k, s] : total) print_row(k, s);

  if (!grid_rows.empty()) {
    std::printf("\n## Cost per frame against the number of holes (grid shapes)\n\n");
    std::printf("| holes | n | samples | frames/interval | projection | frames | mean it | ms/frame | ms/iteration |\n"
                "|---:|---:|---|---:|---|---:|---:|---:|---:|\n");
    for (const auto& [h, g] : grid_rows) {
      std::string gs;
      for (int v : g.samples) gs += (gs.empty() ? "" : ",") + std::to_string(v);
      for (const auto& [k, s] : g.stats)
        std::printf("| %d | %d | %s | %d | %s | %ld | %.2f | %.1f | %.2f |\n", h, g.n, gs.c_str(), k.first, projection_label(k.second),
                    s.frames(), s.mean(), s.ms_per_frame(), s.iterations.empty() ? NAN : s.ms / std::max(1.0, s.mean() * static_cast<double>(s.frames())));
    }
  }

  // Targets (issue #20).
  long cap = 0;
  for (const auto& [k, s] : total) cap += s.at_cap;
  std::vector<std::string> worse;  // shapes where PartProj's mean exceeds Delete's at some frame count
  for (const auto& [shape, m] : by_shape)
    for (int F : frame_counts) {
      const auto pp = m.find({F, HessianProjection::PartProj}), de = m.find({F, HessianProjection::Delete});
      if (pp != m.end() && de != m.end() && pp->second.frames() && de->second.frames() && pp->second.mean() > de->second.mean())
        worse.push_back(shape + "@" + std::to_string(F));
    }
  auto mean_at = [&](int F) {
    const auto it = total.find({F, HessianProjection::PartProj});
    return it == total.end() || !it->second.frames() ? NAN : it->second.mean();
  };
  const bool have_both = std::count(projections.begin(), projections.end(), HessianProjection::PartProj) &&
                         std::count(projections.begin(), projections.end(), HessianProjection::Delete);
  const double m100 = mean_at(100), m500 = mean_at(500);
  std::string summary = "targets: frames at cap " + std::to_string(cap) + (cap == 0 ? " (ok)" : " (FAIL: want 0)");
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
      r["frames_per_interval"] = k.first;
      r["projection"] = projection_label(k.second);
      tot.push_back(r);
    }
    out["total"] = tot;
    out["sequences_run"] = total_sequences - skipped;
    out["keyframes"] = {{"total", keyframes_total}, {"unreached", keyframes_unreached}, {"sequences_not_authored", authoring_failed}};
    out["targets"] = {{"at_cap", cap},
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
