// hsi eval SCENE --points FILE: one map of a scene (a keyframe, a frame of a frames
// file, or the interpolation at any time t) evaluated at chosen points: f, f_z, f_zbar,
// the singular values σ1, σ2 and whether each point lies in the shape.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "hsi/frames_io.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"

namespace hsi::cli {

namespace {

struct EvalOptions {
  std::string scene, points, frames, out, format;
  int keyframe = -1, frame = -1;
  double time = std::nan("");
};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the points file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Points as JSON ([[x, y], ...] or {"points": [[x, y], ...]}) or CSV (x,y per line; a
// first line that is not numbers is a header; blank lines and lines from '#' skipped).
std::vector<cd> read_points(const std::string& path) {
  const std::string text = read_text(path);
  std::vector<cd> out;
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && (text[first] == '[' || text[first] == '{')) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
      throw InputError(path + ": invalid JSON: " + std::string(e.what()).substr(0, 300));
    }
    const nlohmann::json* a = &j;
    if (j.is_object()) {
      if (!j.contains("points")) throw InputError(path + ": expected [[x, y], ...] or {\"points\": [[x, y], ...]}");
      a = &j["points"];
    }
    if (!a->is_array()) throw InputError(path + ": points: expected an array of [x, y]");
    for (size_t i = 0; i < a->size(); ++i) {
      const nlohmann::json& p = (*a)[i];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
        throw InputError(path + ": points[" + std::to_string(i) + "]: expected [x, y] (two numbers)");
      out.emplace_back(p[0].get<double>(), p[1].get<double>());
    }
  } else {
    std::istringstream in(text);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (const size_t c = line.find('#'); c != std::string::npos) line.resize(c);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      for (char& ch : line)
        if (ch == ';' || ch == '\t') ch = ',';
      double x = 0, y = 0;
      char comma = 0, extra = 0;
      std::istringstream fields(line);
      if (fields >> x >> comma >> y && comma == ',' && !(fields >> extra)) {
        out.emplace_back(x, y);
      } else if (out.empty() && n == 1) {
        continue;  // a header
      } else {
        throw InputError(path + ": line " + std::to_string(n) + ": expected two numbers \"x,y\", got \"" + line.substr(0, 60) + "\"");
      }
    }
  }
  for (size_t i = 0; i < out.size(); ++i)
    if (!std::isfinite(out[i].real()) || !std::isfinite(out[i].imag()))
      throw InputError(path + ": point " + std::to_string(i) + " is not finite");
  if (out.empty()) throw InputError(path + ": no points");
  return out;
}

// The map to evaluate, on its cage, and a line saying what it is.
struct Chosen {
  Cage cage;
  HarmonicMap map;
  std::string what;
  double t = 0;
  bool certified = false;
};

Chosen choose_map(const EvalOptions& o, Scene& scene) {
  Chosen c;
  if (!o.frames.empty()) {
    const FrameFile file = read_frames(o.frames);
    if (o.frame < 0 || o.frame >= static_cast<int>(file.frames.size()))
      throw InputError(o.frames + ": has " + std::to_string(file.frames.size()) + " frames (0 to " +
                       std::to_string(file.frames.size() - 1) + "); --frame " + std::to_string(o.frame) + " is not one");
    const StoredFrame& f = file.frames[static_cast<size_t>(o.frame)];
    c.cage = file.cage;
    c.map = f.map;
    c.t = f.t;
    c.certified = f.certified;
    c.what = "frame " + std::to_string(o.frame) + " of " + o.frames + " (t = " + std::to_string(f.t) + ", " +
             (f.certified ? "certified locally injective" : "NOT CERTIFIED") +
             (f.converged ? "" : std::string(", NOT CONVERGED: ") + stop_name(stored_stop(f, static_cast<size_t>(o.frame)))) + ")";
    if (file.cage.loops.size() != static_cast<size_t>(scene.shape.loop_count()))
      throw InputError(o.frames + ": its cage has " + std::to_string(file.cage.loops.size()) + " loops; the scene's shape has " +
                       std::to_string(scene.shape.loop_count()) + ": not this scene's frames");
    return c;
  }
  if (scene.keyframes.empty()) throw InputError(o.scene + ": the scene has no keyframes");
  const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene);
  solve_scene_keyframes(scene, *setup);  // certified, or an InputError saying why not
  c.cage = setup->cage;
  if (o.keyframe >= 0) {
    if (o.keyframe >= static_cast<int>(scene.keyframes.size()))
      throw InputError(o.scene + ": has " + std::to_string(scene.keyframes.size()) + " keyframes (0 to " +
                       std::to_string(scene.keyframes.size() - 1) + "); --keyframe " + std::to_string(o.keyframe) + " is not one");
    const Keyframe& k = scene.keyframes[static_cast<size_t>(o.keyframe)];
    c.map = *k.coefficients;
    c.t = k.time;
    c.certified = true;
    c.what = "keyframe " + std::to_string(o.keyframe) + " (t = " + std::to_string(k.time) + ", certified locally injective)";
    return c;
  }
  if (scene.keyframes.size() < 2) throw InputError(o.scene + ": --time needs at least two keyframes to interpolate between");
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : scene.keyframes) {
    times.push_back(k.time);
    maps.push_back(*k.coefficients);
  }
  if (!(o.time >= times.front() && o.time <= times.back()))
    throw InputError("--time " + std::to_string(o.time) + " lies outside the keyframes' times [" + std::to_string(times.front()) +
                     ", " + std::to_string(times.back()) + "]");
  Interpolator interp(*setup, times, maps);
  const FrameResult f = interp.frame(o.time);
  c.map = f.map;
  c.t = f.t;
  c.certified = f.certified;
  c.what = "the interpolation at t = " + std::to_string(f.t) + " (" + (f.keyframe ? "a keyframe, " : "solved from the keyframe before, ") +
           (f.certified ? "certified locally injective" : "NOT CERTIFIED") + (f.converged ? "" : std::string(", NOT CONVERGED: ") + to_string(f.stop)) +
           ")";
  return c;
}

void run(const EvalOptions& o) {
  const int sources = (o.keyframe >= 0) + !o.frames.empty() + !std::isnan(o.time);
  if (sources != 1) throw InputError("give exactly one of --keyframe K, --frames FILE --frame I, or --time T");
  if (!o.frames.empty() && o.frame < 0) throw InputError("--frames needs --frame I (which frame)");
  if (o.frames.empty() && o.frame >= 0) throw InputError("--frame needs --frames FILE");
  Scene scene = load_scene(o.scene);
  const std::vector<cd> points = read_points(o.points);
  const Chosen c = choose_map(o, scene);

  // Values only at points of the shape (its closure, within 1e-9 of its size): elsewhere the
  // basis is not the map (and is singular on the cage and at the hole points).
  const double eps = 1e-9 * bounding_box(scene.shape).diagonal();
  std::vector<cd> inside_points;
  std::vector<int> inside;  // index into inside_points, or -1
  for (const cd& p : points) {
    const bool in = point_in_shape(scene.shape, p) || boundary_distance(scene.shape, p) <= eps;
    inside.push_back(in ? static_cast<int>(inside_points.size()) : -1);
    if (in) inside_points.push_back(p);
  }
  const MapValues v = evaluate_map(c.cage, c.map, inside_points);

  const std::string format = !o.format.empty() ? o.format
                             : (o.out.size() >= 5 && o.out.substr(o.out.size() - 5) == ".json") ? "json"
                                                                                                   : "csv";
  std::ostringstream s;
  s.precision(17);
  nlohmann::json j;
  if (format == "json") {
    j["map"] = {{"what", c.what}, {"t", c.t}, {"certified", c.certified}};
    j["points"] = nlohmann::json::array();
  } else {
    s << "# " << c.what << "\n";
    s << "x,y,inside,f_x,f_y,f_z_re,f_z_im,f_zbar_re,f_zbar_im,sigma1,sigma2\n";
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const cd p = points[i];
    const int k = inside[i];
    if (format == "json") {
      nlohmann::json pj{{"x", p.real()}, {"y", p.imag()}, {"inside", k >= 0}};
      if (k >= 0) {
        const cd f = v.f(k), fz = v.f_z(k), fzbar = std::conj(v.fzbar_conj(k));
        pj["f"] = {f.real(), f.imag()};
        pj["f_z"] = {fz.real(), fz.imag()};
        pj["f_zbar"] = {fzbar.real(), fzbar.imag()};
        pj["sigma1"] = std::abs(fz) + std::abs(fzbar);
        pj["sigma2"] = std::abs(fz) - std::abs(fzbar);
      }
      j["points"].push_back(pj);
    } else {
      s << p.real() << "," << p.imag() << "," << (k >= 0 ? 1 : 0);
      if (k >= 0) {
        const cd f = v.f(k), fz = v.f_z(k), fzbar = std::conj(v.fzbar_conj(k));
        s << "," << f.real() << "," << f.imag() << "," << fz.real() << "," << fz.imag() << "," << fzbar.real() << ","
          << fzbar.imag() << "," << std::abs(fz) + std::abs(fzbar) << "," << std::abs(fz) - std::abs(fzbar);
      } else {
        s << ",,,,,,,,";
      }
      s << "\n";
    }
  }
  const std::string text = format == "json" ? j.dump(1) + "\n" : s.str();
  const int outside = static_cast<int>(points.size() - inside_points.size());
  if (o.out.empty()) {
    std::fwrite(text.data(), 1, text.size(), stdout);
    std::fprintf(stderr, "hsi eval: %s at %zu points (%d outside the shape: no values)\n", c.what.c_str(), points.size(), outside);
  } else {
    write_file_atomic(o.out, text);
    std::printf("wrote %s: %s at %zu points (%d outside the shape: no values)\n", o.out.c_str(), c.what.c_str(), points.size(),
                outside);
  }
}

}  // namespace

void register_eval(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Evaluate one map of a scene at chosen points: f, f_z, f_zbar and the singular values\n"
      "sigma1 = |f_z| + |f_zbar|, sigma2 = |f_z| - |f_zbar| (negative where orientation flips).\n"
      "The map: --keyframe K (solved from its targets if it has no coefficients), --frames\n"
      "FILE --frame I (a frame of hsi interpolate's frames.hsif), or --time T (the\n"
      "interpolation at T, solved from the keyframe before T). Points from --points: JSON\n"
      "[[x, y], ...] or {\"points\": [...]}, or CSV lines x,y (a header line allowed). Points\n"
      "outside the shape get inside = 0 and no values. Output: CSV (a '# what' line, a header,\n"
      "one line per point) or JSON (by -o's extension or --format), to -o or stdout.");
  cmd->add_option("scene", o->scene, "Scene file (.json)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--points", o->points, "Points file (.json or .csv)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--keyframe", o->keyframe, "Evaluate keyframe K (0-based)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames", o->frames, "A frames file (.hsif) of this scene")->check(CLI::ExistingFile);
  cmd->add_option("--frame", o->frame, "Which frame of --frames (0-based)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--time", o->time, "Evaluate the interpolation at this time");
  cmd->add_option("-o,--output", o->out, "Write here (.csv or .json); default: stdout");
  cmd->add_option("--format", o->format, "csv or json (default: by -o's extension, else csv)")->check(CLI::IsMember({"csv", "json"}));
  cmd->callback([o] { run(*o); });
}

}  // namespace hsi::cli
