// The Newton stress corpus (bench/stress/, issue #20), read by bench_stress and by the
// test slice (tests/test_stress.cpp): shapes (scene files) and sequences of 2 or 3
// keyframes given as handles + targets, exactly what an animator writes in a scene.
// A sequence becomes a Scene (its shape's scene with the sequence's |G|, handles and
// keyframe targets; any keyframes the shape's scene had are dropped), and its
// keyframes are made by solve_scene_keyframes, the authoring path.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "hsi/keyframes.h"
#include "hsi/scene_io.h"

namespace hsi::stress {

struct ShapeEntry {
  std::string name, scene, family;  // scene: relative to the corpus folder
};

struct Sequence {
  std::string id, shape, kind, description;
  int samples = 10000;
  std::vector<cd> handles;
  std::vector<std::vector<cd>> targets;  // per keyframe, at times 0, 1, ...
  std::vector<double> times;
};

struct Corpus {
  std::filesystem::path dir;
  int seed = 0;
  std::vector<ShapeEntry> shapes;
  std::vector<Sequence> sequences;
  const ShapeEntry& shape(const std::string& name) const {
    for (const ShapeEntry& s : shapes)
      if (s.name == name) return s;
    throw std::runtime_error("stress corpus: no shape " + name);
  }
  const Sequence& sequence(const std::string& id) const {
    for (const Sequence& q : sequences)
      if (q.id == id) return q;
    throw std::runtime_error("stress corpus: no sequence " + id);
  }
};

inline Corpus load_corpus(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read the stress corpus " + file.string());
  const nlohmann::json j = nlohmann::json::parse(in);
  if (j.value("hsi_stress_corpus", 0) != 1) throw std::runtime_error(file.string() + ": not a version-1 stress corpus");
  Corpus c;
  c.dir = file.parent_path();
  c.seed = j.value("seed", 0);
  auto point = [](const nlohmann::json& p) { return cd(p.at(0).get<double>(), p.at(1).get<double>()); };
  for (const auto& s : j.at("shapes")) c.shapes.push_back({s.at("name"), s.at("scene"), s.value("family", "")});
  for (const auto& s : j.at("sequences")) {
    Sequence q;
    q.id = s.at("id");
    q.shape = s.at("shape");
    q.kind = s.value("kind", "");
    q.description = s.value("description", "");
    q.samples = s.value("samples", 10000);
    for (const auto& p : s.at("handles")) q.handles.push_back(point(p));
    for (const auto& k : s.at("keyframes")) {
      q.times.push_back(k.at("time").get<double>());
      std::vector<cd> t;
      for (const auto& p : k.at("targets")) t.push_back(point(p));
      q.targets.push_back(std::move(t));
    }
    c.sequences.push_back(std::move(q));
  }
  return c;
}

inline std::string read_file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scene file's text with every loop of its shape listed the other way round
// (each of shape.outer and shape.holes[i] reversed): the same shape given in the other
// orientation (bench_stress --reverse-loops). Everything else is kept as it is.
inline std::string reverse_shape_loops(const std::string& scene_text, const std::string& source = "scene") {
  nlohmann::json j = nlohmann::json::parse(scene_text);
  nlohmann::json* shape = j.is_object() && j.contains("shape") ? &j["shape"] : nullptr;
  if (!shape || !shape->is_object() || !shape->contains("outer") || !(*shape)["outer"].is_array())
    throw std::runtime_error(source + ": no shape.outer to reverse");
  auto reverse = [](nlohmann::json& loop) {
    if (loop.is_array()) std::reverse(loop.begin(), loop.end());  // anything else: parse_scene says what is wrong
  };
  reverse((*shape)["outer"]);
  if (shape->contains("holes") && (*shape)["holes"].is_array())
    for (nlohmann::json& h : (*shape)["holes"]) reverse(h);
  return j.dump(1);
}

// The text of a shape's scene file as the corpus reads it: as given, or with its
// loops reversed. Its bytes are the keyframe cache's key (stress_cache.h).
inline std::string shape_file_text(const Corpus& c, const ShapeEntry& s, bool reverse_loops = false) {
  const std::filesystem::path file = c.dir / s.scene;
  const std::string text = read_file_bytes(file);
  return reverse_loops ? reverse_shape_loops(text, file.string()) : text;
}

// The shape's scene (from shape_file_text's `text`) with its cage fixed (the user
// cage, or the automatic one built now), without handles or keyframes.
inline Scene shape_scene(const Corpus& c, const ShapeEntry& s, const std::string& text) {
  const std::filesystem::path file = c.dir / s.scene;
  Scene scene = parse_scene(text, file.parent_path(), file.string());
  scene.name = s.name;
  scene.cage = scene_cage(scene);
  scene.handles.clear();
  scene.keyframes.clear();
  return scene;
}
inline Scene load_shape(const Corpus& c, const ShapeEntry& s, bool reverse_loops = false) {
  return shape_scene(c, s, shape_file_text(c, s, reverse_loops));
}

// The sequence as a scene: handles and keyframe targets (no coefficients), |G| =
// samples when positive, else the sequence's.
inline Scene sequence_scene(const Scene& shape, const Sequence& q, int samples = 0) {
  Scene scene = shape;
  scene.samples = samples > 0 ? samples : q.samples;
  scene.handles = q.handles;
  scene.keyframes.clear();
  for (size_t k = 0; k < q.targets.size(); ++k) {
    Keyframe kf;
    kf.time = q.times[k];
    kf.targets = q.targets[k];
    scene.keyframes.push_back(std::move(kf));
  }
  return scene;
}

// A sequence with its keyframes authored (certified maps), ready for an Interpolator.
struct Authored {
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  // Per keyframe: its targets were reached (else its drag would fold and the closest
  // certified map was kept), and the largest handle-to-target distance relative to
  // the shape's size.
  std::vector<char> reached;
  std::vector<double> target_error;
  int unreached = 0;            // keyframes not reached
  double max_target_error = 0;  // over the keyframes
  double ms = 0;                // authoring time (solver), summed over the keyframes
};

inline Authored author(Scene& scene, const ShapeSetup& setup, const KeyframeOptions& options = {}) {
  Authored a;
  const std::vector<SceneKeyframe> solved = solve_scene_keyframes(scene, setup, options);
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    const bool solved_now = k < solved.size() && solved[k].solved;
    const bool reached = !solved_now || solved[k].result.reached;
    const double error = solved_now ? solved[k].result.max_target_error / setup.size : 0.0;
    a.times.push_back(scene.keyframes[k].time);
    a.maps.push_back(*scene.keyframes[k].coefficients);
    a.reached.push_back(reached);
    a.target_error.push_back(error);
    a.unreached += !reached;
    a.max_target_error = std::max(a.max_target_error, error);
    if (solved_now) a.ms += solved[k].result.ms;
  }
  return a;
}

}  // namespace hsi::stress
