// Scene → certified keyframes → interpolated sequence → report (hsi/scene_sequence.h).
#include "hsi/scene_sequence.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "hsi/keyframes.h"

namespace hsi {

int SceneSequence::uncertified() const {
  int n = 0;
  for (const FrameResult& f : frames) n += !f.certified;
  return n;
}

FrameFile SceneSequence::frame_file() const {
  FrameFile ff;
  ff.cage = setup->cage;
  for (const FrameResult& f : frames) {
    ff.frames.push_back({f.t, f.certified, f.keyframe, f.converged, static_cast<uint32_t>(f.iterations), f.energy, f.map});
    ff.frames.back().overlaps = f.overlap.overlaps();
    ff.frames.back().stop = f.stop;
  }
  return ff;
}

std::vector<KeyTiming> scene_timings(const Scene& scene) {
  std::vector<KeyTiming> t;
  for (const Keyframe& k : scene.keyframes) t.push_back(k.timing);
  if (std::all_of(t.begin(), t.end(), [](KeyTiming k) { return k == KeyTiming::Linear; })) t.clear();
  return t;
}

std::shared_ptr<const ShapeSetup> scene_setup(Scene& scene, int samples, double hessian_ratio) {
  try {
    if (!scene.cage) scene.cage = scene_cage(scene);
    return make_shape_setup(scene, samples, hessian_ratio);
  } catch (const InputError& e) {
    rethrow_in_scene(scene, e);
  }
}

SceneSequence interpolate_scene(Scene& scene, const SceneSequenceOptions& options,
                                const std::function<void(const FrameResult&, int, int)>& progress,
                                std::unique_ptr<NewtonCore> core, std::shared_ptr<const ShapeSetup> setup) {
  if (scene.keyframes.size() < 2)
    throw InputError((scene.source.empty() ? "scene '" + scene.name + "'" : scene.source) + ": interpolation needs at least two keyframes (it has " +
                     std::to_string(scene.keyframes.size()) + "); " + kHowToAddKeyframes);
  if (options.frames_per_interval <= 0 && options.frames < 2)
    throw InputError("a sequence needs at least 2 frames (got " + std::to_string(options.frames) + ")");
  if (!setup) setup = scene_setup(scene, options.samples, options.hessian_ratio);
  solve_scene_keyframes(scene, *setup);
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : scene.keyframes) {
    times.push_back(k.time);
    maps.push_back(*k.coefficients);
  }
  if (!core) core = make_cpu_newton_core(setup->D_G, setup->H);
  InterpolationOptions io = options.interpolation;
  if (io.timing.empty()) io.timing = scene_timings(scene);
  Interpolator interp(*setup, times, maps, io, std::move(core));
  SceneSequence seq;
  seq.setup = setup;
  const auto t0 = std::chrono::steady_clock::now();
  seq.options = io;
  seq.frames = interp.sequence(sequence_times(times, options.frames, options.frames_per_interval), progress);
  seq.total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return seq;
}

SequenceSummary summarize(const std::vector<FrameResult>& frames, double total_s) {
  SequenceSummary s;
  s.frames = static_cast<int>(frames.size());
  s.total_s = total_s;
  int solved = 0;
  double it = 0, ms = 0;
  for (const FrameResult& f : frames) {
    s.certified += f.certified;
    s.within_bounds += f.bound_excess <= 1e-9;
    s.max_bound_excess = std::max(s.max_bound_excess, f.bound_excess);
    s.overlapping += f.overlap.overlaps();
    s.not_converged += !f.converged;
    ++s.stops[static_cast<size_t>(f.stop)];
    if (f.certified && std::isfinite(f.certified_bound_excess)) {
      s.within_certified_bounds += f.certified_bound_excess <= 1e-9;
      s.max_certified_bound_excess = std::max(s.max_certified_bound_excess, f.certified_bound_excess);
    }
    if (!f.keyframe) {
      ++solved;
      it += f.iterations;
      ms += f.ms;
      s.max_ms = std::max(s.max_ms, f.ms);
    }
  }
  s.uncertified = s.frames - s.certified;
  s.mean_iterations = solved ? it / solved : 0.0;
  s.mean_ms = solved ? ms / solved : 0.0;
  return s;
}

std::vector<SummaryField> summary_fields(const SequenceSummary& s) {
  return {{"frames", double(s.frames), true},
          {"certified", double(s.certified), true},
          {"uncertified", double(s.uncertified), true},
          {"not_converged", double(s.not_converged), true},
          {"mean_iterations", s.mean_iterations, false},
          {"mean_ms", s.mean_ms, false},
          {"max_ms", s.max_ms, false},
          {"total_s", s.total_s, false},
          {"frames_within_keyframe_bounds", double(s.within_bounds), true},
          {"max_bound_excess", s.max_bound_excess, false},
          {"overlapping", double(s.overlapping), true},
          {"frames_within_keyframe_certified_bounds", double(s.within_certified_bounds), true},
          {"max_certified_bound_excess", s.max_certified_bound_excess, false}};
}

namespace {

nlohmann::json summary_json(const SequenceSummary& s) {
  nlohmann::json j = nlohmann::json::object();
  for (const SummaryField& f : summary_fields(s))
    j[f.name] = f.integer ? nlohmann::json(static_cast<long long>(f.value)) : nlohmann::json(f.value);
  return j;
}

// A frame's global-overlap check (overlap.h): whether it ran, the crossings of the
// boundary's image at the breakpoints, and the first one.
nlohmann::json overlap_json(const OverlapResult& o) {
  nlohmann::json j = {{"checked", o.checked}, {"crossings", o.crossings}, {"breakpoints", o.points}};
  if (o.overlaps())
    j["first"] = {{"loop_a", o.loop_a}, {"edge_a", o.edge_a}, {"loop_b", o.loop_b}, {"edge_b", o.edge_b},
                  {"point", {o.point.real(), o.point.imag()}}};
  return j;
}

nlohmann::json distortion_json(const Distortion& d) {
  // NaN (a certified bound of an uncertified frame) is written as null.
  auto v = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); };
  return {{"sigma1_max", v(d.sigma1_max)}, {"sigma2_min", v(d.sigma2_min)}, {"conformal_max", v(d.conformal_max)},
          {"isometric_max", v(d.isometric_max)}};
}
}  // namespace

std::string report_json(const Scene& scene, const SceneSequence& seq, const std::string& scene_path) {
  nlohmann::json rep;
  rep["scene"] = scene_path;
  rep["name"] = scene.name;
  rep["samples"] = seq.setup->G.size();
  rep["hessian_samples"] = seq.setup->H.size();
  rep["n"] = seq.setup->map_space.n();
  rep["projection"] = to_string(seq.options.projection);
  rep["tolerance"] = seq.options.tolerance;
  rep["max_iterations"] = seq.options.max_iterations;
  // How each keyframe interval was travelled (timing.h): one name per keyframe, or one for all.
  rep["timing"] = nlohmann::json::array();
  for (KeyTiming k : seq.options.timing) rep["timing"].push_back(to_string(k));
  if (seq.options.timing.empty()) rep["timing"].push_back(to_string(KeyTiming::Linear));
  rep["distortion_kinds"] = {
      {"sampled",
       "sigma1_max, sigma2_min, conformal_max, isometric_max (also under distortion_sampled), bound, bound_excess: sampled "
       "at the certificate's breakpoints (observed maxima/minima, not bounds)"},
      {"certified",
       "distortion_certified, certified_bound, certified_bound_excess: the certificate's bounds over the boundary, so over "
       "the shape (sigma2_min a lower bound, the others upper bounds; isometric_max derived from the sigma bounds); null "
       "when the frame is not certified"}};
  nlohmann::json fr = nlohmann::json::array();
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const FrameResult& f = seq.frames[i];
    fr.push_back({{"frame", i},
                  {"t", f.t},
                  {"keyframe", f.keyframe},
                  {"held", f.held},
                  {"certified", f.certified},
                  {"converged", f.converged},
                  {"stop", to_string(f.stop)},
                  {"iterations", f.iterations},
                  {"predicted_start", f.predicted},
                  {"energy", f.energy},
                  {"ms", f.ms},
                  {"sigma1_max", f.distortion.sigma1_max},
                  {"sigma2_min", f.distortion.sigma2_min},
                  {"conformal_max", f.distortion.conformal_max},
                  {"isometric_max", f.distortion.isometric_max},
                  {"distortion_sampled", distortion_json(f.distortion)},
                  {"distortion_certified", distortion_json(f.distortion_certified)},
                  {"bound", distortion_json(f.bound)},
                  {"certified_bound", distortion_json(f.certified_bound)},
                  {"bound_excess", f.bound_excess},
                  {"certified_bound_excess", std::isfinite(f.certified_bound_excess) ? nlohmann::json(f.certified_bound_excess)
                                                                                     : nlohmann::json(nullptr)},
                  {"certificate", {{"sigma1_max", f.certificate.sigma1_max}, {"sigma2_min", f.certificate.sigma2_min},
                                   {"k_max", f.certificate.k_max}, {"reason", f.certificate.reason}}},
                  {"message", f.message},
                  {"overlaps", f.overlap.overlaps()},
                  {"overlap", overlap_json(f.overlap)}});
  }
  const SequenceSummary sum = summarize(seq.frames, seq.total_s);
  rep["summary"] = summary_json(sum);
  // Why frames stopped, by NewtonStop's names ("converged", "iteration limit", ...): zeros left out.
  nlohmann::json stops = nlohmann::json::object();
  for (int i = 0; i < kNewtonStopCount; ++i)
    if (sum.stops[static_cast<size_t>(i)] > 0) stops[to_string(static_cast<NewtonStop>(i))] = sum.stops[static_cast<size_t>(i)];
  rep["summary"]["stops"] = stops;
  rep["frames"] = fr;
  return rep.dump(1) + "\n";
}

std::string report_csv(const SceneSequence& seq) {
  // sigma1_max..bound_excess: sampled at the certificate's breakpoints; certified_*:
  // the certificate's bounds, empty when the frame is not certified.
  std::string out =
      "frame,t,keyframe,certified,converged,iterations,energy,ms,sigma1_max,sigma2_min,conformal_max,isometric_max,"
      "bound_sigma1_max,bound_sigma2_min,bound_conformal_max,bound_isometric_max,bound_excess,overlaps,crossings,"
      "certified_sigma1_max,certified_sigma2_min,certified_conformal_max,certified_isometric_max,"
      "certified_bound_sigma1_max,certified_bound_sigma2_min,certified_bound_conformal_max,certified_bound_isometric_max,"
      "certified_bound_excess\n";
  auto num = [](double x) {
    if (!std::isfinite(x)) return std::string(",");
    char b[40];
    std::snprintf(b, sizeof b, ",%.17g", x);
    return std::string(b);
  };
  char line[512];
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const FrameResult& f = seq.frames[i];
    std::snprintf(line, sizeof line, "%zu,%.17g,%d,%d,%d,%d,%.17g,%.6g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d\n", i,
                  f.t, f.keyframe ? 1 : 0, f.certified ? 1 : 0, f.converged ? 1 : 0, f.iterations, f.energy, f.ms,
                  f.distortion.sigma1_max, f.distortion.sigma2_min, f.distortion.conformal_max, f.distortion.isometric_max,
                  f.bound.sigma1_max, f.bound.sigma2_min, f.bound.conformal_max, f.bound.isometric_max, f.bound_excess,
                  f.overlap.overlaps() ? 1 : 0, f.overlap.crossings);
    out += line;
    out.pop_back();  // the newline: the certified columns follow
    const Distortion& c = f.distortion_certified;
    const Distortion& cb = f.certified_bound;
    for (double x : {c.sigma1_max, c.sigma2_min, c.conformal_max, c.isometric_max, cb.sigma1_max, cb.sigma2_min, cb.conformal_max,
                     cb.isometric_max, f.certified_bound_excess})
      out += num(x);
    out += "\n";
  }
  return out;
}

}  // namespace hsi
