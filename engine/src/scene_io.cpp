// Scene JSON reading and writing (format documented in hsi/scene_io.h).
#include "hsi/scene_io.h"
#include "hsi/sample_limits.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hsi/keyframes.h"  // off_shape_reason: the one check of a handle's place
#include "hsi/map_space.h"

namespace hsi {
namespace {
using json = nlohmann::json;

struct Ctx {
  std::string source;
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InputError(source + ": " + (path.empty() ? "" : path + ": ") + what);
  }
};

std::string type_name(const json& j) { return j.type_name(); }

double number(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_number()) c.fail(path, "expected a number, got " + type_name(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) c.fail(path, "is not a finite number");
  return v;
}

cd point(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 2) c.fail(path, "expected a point [x, y], got " + (j.is_array() ? "an array of " + std::to_string(j.size()) : type_name(j)));
  return {number(c, j[0], path + "[0]"), number(c, j[1], path + "[1]")};
}

std::vector<cd> points(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_array()) c.fail(path, "expected an array of points [[x, y], ...], got " + type_name(j));
  std::vector<cd> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(point(c, j[i], path + "[" + std::to_string(i) + "]"));
  return out;
}

VectorXcd coefficients(const Ctx& c, const json& j, const std::string& path) {
  const std::vector<cd> v = points(c, j, path);
  VectorXcd out(static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out(static_cast<Eigen::Index>(i)) = v[i];
  return out;
}

// The coefficient layouts a keyframe may be given in (scene_io.h, "layout").
enum class Layout { Full, Reduced };

// A keyframe's φ or ψ as read (`layout`, over the cage loops in the file's order and
// orientation) to the full layout over the loaded cage, whose loops parse_scene turned
// to the normal orientation: a reversed loop takes its coefficients with it, so each
// coefficient stays with its vertex. The reduced layout's dropped columns (the first
// two vertices of each hole loop: map_space.h) become 0, which leaves f unchanged.
VectorXcd to_full_layout(const VectorXcd& given, Layout layout, const Cage& file_cage, const std::vector<bool>& reversed) {
  VectorXcd full = VectorXcd::Zero(basis_size(file_cage));
  if (layout == Layout::Full) {
    full = given;
  } else {
    const std::vector<int> active = MapSpace(file_cage, Gauge::Map).active();
    for (size_t a = 0; a < active.size(); ++a) full(active[a]) = given(static_cast<Eigen::Index>(a));
  }
  for (int k = 0; k < static_cast<int>(file_cage.loops.size()); ++k)
    if (reversed[static_cast<size_t>(k)])
      full.segment(file_cage.loop_offset(k), static_cast<Eigen::Index>(file_cage.loops[static_cast<size_t>(k)].size())).reverseInPlace();
  return full;
}

// Text from the file quoted in a message: non-printable bytes as \xNN, and cut to a
// readable length (a 100,000-digit number must not fill the terminal).
std::string excerpt(const std::string& text, size_t max_chars = 40) {
  std::string out;
  for (size_t i = 0; i < std::min(text.size(), max_chars); ++i) {
    const auto u = static_cast<unsigned char>(text[i]);
    if (u >= 0x20 && u < 0x7f) {
      out += text[i];
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", u);
      out += hex;
    }
  }
  if (text.size() > max_chars) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
}

// nlohmann's messages quote the offending token ('...'): that part cut to an excerpt.
std::string cut_quotes(const std::string& msg) {
  const size_t open = msg.find('\'');
  const size_t close = msg.rfind('\'');
  if (open == std::string::npos || close <= open) return excerpt(msg, 300);
  return excerpt(msg.substr(0, open + 1), 300) + excerpt(msg.substr(open + 1, close - open - 1)) + excerpt(msg.substr(close), 300);
}

// Byte offset of `token` standing alone as a number in `text` (outside strings), or npos.
size_t find_number_token(const std::string& text, const std::string& token) {
  if (token.empty()) return std::string::npos;
  const auto part_of_number = [](char ch) { return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '+' || ch == '-'; };
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (in_string) {
      if (ch == '\\') ++i;
      else if (ch == '"') in_string = false;
    } else if (ch == '"') {
      in_string = true;
    } else if (text.compare(i, token.size(), token) == 0 && (i == 0 || !part_of_number(text[i - 1])) &&
               (i + token.size() == text.size() || !part_of_number(text[i + token.size()]))) {
      return i;
    }
  }
  return std::string::npos;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) == std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (same ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// Refuses a key the format does not have (scene_io.h): a misspelt optional key would
// otherwise fall back to its default without a word. Names the key's JSON path and the
// nearest known key.
void check_keys(const Ctx& c, const json& obj, const std::string& path, std::initializer_list<const char*> known) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    const std::string& key = it.key();
    if (std::any_of(known.begin(), known.end(), [&](const char* k) { return key == k; })) continue;
    const std::string cut = key.substr(0, 200);  // the distance of a huge key says nothing more
    const char* nearest = *known.begin();
    for (const char* k : known)
      if (edit_distance(cut, k) < edit_distance(cut, nearest)) nearest = k;
    std::string all;
    for (const char* k : known) all += std::string(all.empty() ? "" : ", ") + "\"" + k + "\"";
    c.fail(path.empty() ? excerpt(key) : path + "." + excerpt(key),
           "unknown key; the nearest known key is \"" + std::string(nearest) + "\" (" + (path.empty() ? "the top level" : path) +
               " takes " + all + ")");
  }
}

const json* field(const json& obj, const char* key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

json to_json(const std::vector<cd>& pts) {
  json a = json::array();
  for (const cd& p : pts) a.push_back({p.real(), p.imag()});
  return a;
}
json to_json(const VectorXcd& v) {
  json a = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back({v(i).real(), v(i).imag()});
  return a;
}

std::string line_col(const std::string& text, size_t byte) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i < std::min(byte, text.size()); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}
}  // namespace

std::filesystem::path Scene::texture_path() const {
  if (texture.empty() || texture.is_absolute()) return texture;
  return base_dir / texture;
}

std::array<double, 4> Scene::texture_rect_or_bounds() const {
  if (texture_rect) return *texture_rect;
  const BoundingBox bb = bounding_box(shape);
  return {bb.lo.real(), bb.lo.imag(), bb.hi.real(), bb.hi.imag()};
}

Scene parse_scene(const std::string& text, const std::filesystem::path& base_dir, const std::string& source) {
  const Ctx c{source};
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line L, column C: why";
    // keep only "why" (the location is ours, from the byte offset), with bytes that
    // are not printable ASCII (a bad UTF-8 byte it quotes) written as \xNN.
    std::string msg = e.what();
    if (auto p = msg.find("] "); p != std::string::npos) msg = msg.substr(p + 2);
    if (msg.rfind("parse error", 0) == 0)
      if (auto p = msg.find(": "); p != std::string::npos) msg = msg.substr(p + 2);
    c.fail("", "invalid JSON at " + line_col(text, e.byte > 0 ? e.byte - 1 : 0) + ": " + cut_quotes(msg));
  } catch (const json::exception& e) {
    // E.g. a number too large for a double (1e400): nlohmann reports it as out_of_range,
    // quoting the number but giving no place; the place is found from the number.
    std::string msg = e.what();
    if (auto p = msg.find("] "); p != std::string::npos) msg = msg.substr(p + 2);
    std::string where;
    const size_t open = msg.find('\''), close = msg.rfind('\'');
    if (open != std::string::npos && close > open)
      if (const size_t at = find_number_token(text, msg.substr(open + 1, close - open - 1)); at != std::string::npos)
        where = " at " + line_col(text, at);
    c.fail("", "invalid JSON" + where + ": " + cut_quotes(msg));
  }
  if (!j.is_object()) c.fail("", "expected a JSON object at the top level, got " + type_name(j));
  const json* version = field(j, "hsi_scene");
  if (!version) c.fail("", "missing \"hsi_scene\" (the format version); is this an hsi scene file?");
  if (!version->is_number_integer()) c.fail("hsi_scene", "expected an integer version, got " + type_name(*version));
  // Compared as written (not narrowed to int, which would read 4294967297 as 1).
  if (version->dump() != "1" && version->dump() != std::to_string(kSceneVersion))
    c.fail("hsi_scene", "unsupported version " + version->dump() + " (this hsi reads versions 1 to " + std::to_string(kSceneVersion) + ")");
  const int file_version = version->dump() == "1" ? 1 : kSceneVersion;
  check_keys(c, j, "", {"hsi_scene", "name", "shape", "texture", "texture_rect", "texture_filter", "cage", "samples", "hessian_ratio", "handles", "keyframes"});
  Scene s;
  s.base_dir = base_dir;
  s.source = source;
  if (const json* n = field(j, "name")) {
    if (!n->is_string()) c.fail("name", "expected a string");
    s.name = n->get<std::string>();
  }
  const json* shape = field(j, "shape");
  if (!shape) c.fail("", "missing \"shape\"");
  if (!shape->is_object()) c.fail("shape", "expected an object with \"outer\" and optional \"holes\"");
  check_keys(c, *shape, "shape", {"outer", "holes"});
  const json* outer = field(*shape, "outer");
  if (!outer) c.fail("shape", "missing \"outer\"");
  s.shape.outer = points(c, *outer, "shape.outer");
  if (const json* holes = field(*shape, "holes")) {
    if (!holes->is_array()) c.fail("shape.holes", "expected an array of loops");
    for (size_t h = 0; h < holes->size(); ++h)
      s.shape.holes.push_back(points(c, (*holes)[h], "shape.holes[" + std::to_string(h) + "]"));
  }
  try {
    validate(s.shape);
  } catch (const InputError& e) {
    c.fail("shape", e.what());
  }
  s.shape = normalize(std::move(s.shape));

  if (const json* t = field(j, "texture")) {
    if (!t->is_string()) c.fail("texture", "expected a file path string");
    s.texture = t->get<std::string>();
  }
  if (const json* f = field(j, "texture_filter")) {
    const std::optional<TextureFilter> tf = f->is_string() ? parse_texture_filter(f->get<std::string>()) : std::nullopt;
    if (!tf) c.fail("texture_filter", "expected \"linear\" or \"nearest\"");
    s.texture_filter = *tf;
  }
  if (const json* r = field(j, "texture_rect")) {
    if (!r->is_array() || r->size() != 4) c.fail("texture_rect", "expected [x0, y0, x1, y1]");
    std::array<double, 4> rect{};
    for (size_t i = 0; i < 4; ++i) rect[i] = number(c, (*r)[i], "texture_rect[" + std::to_string(i) + "]");
    if (!(rect[2] > rect[0] && rect[3] > rect[1])) c.fail("texture_rect", "needs x1 > x0 and y1 > y0");
    s.texture_rect = rect;
  }
  Cage file_cage;              // the user cage as the file gives it (loop order and orientation)
  std::vector<bool> reversed;  // per cage loop: reversed to the normal orientation
  if (const json* cg = field(j, "cage")) {
    if (!cg->is_object()) c.fail("cage", "expected an object");
    check_keys(c, *cg, "cage", {"clearance", "max_vertices_per_loop", "loops", "hole_points"});
    if (const json* v = field(*cg, "clearance")) {
      s.cage_options.clearance = number(c, *v, "cage.clearance");
      if (!(s.cage_options.clearance > 0 && s.cage_options.clearance <= 1))
        c.fail("cage.clearance", "must lie in (0, 1] (the cage's offset as a fraction of the shape's size)");
    }
    if (const json* v = field(*cg, "max_vertices_per_loop")) {
      if (!v->is_number_integer() || v->get<long long>() < 4 || v->get<long long>() > 100000)
        c.fail("cage.max_vertices_per_loop", "expected an integer between 4 and 100,000");
      s.cage_options.max_vertices_per_loop = v->get<int>();
    }
    const json* loops = field(*cg, "loops");
    const json* holes = field(*cg, "hole_points");
    if (loops || holes) {
      if (!loops || !holes) c.fail("cage", "a user cage needs both \"loops\" and \"hole_points\" (use [] for no holes)");
      if (!loops->is_array()) c.fail("cage.loops", "expected an array of loops");
      Cage cage;
      for (size_t k = 0; k < loops->size(); ++k)
        cage.loops.push_back(points(c, (*loops)[k], "cage.loops[" + std::to_string(k) + "]"));
      cage.hole_points = points(c, *holes, "cage.hole_points");
      file_cage = cage;
      reversed.assign(cage.loops.size(), false);
      for (size_t k = 0; k < cage.loops.size(); ++k) {
        if (cage.loops[k].size() < 3) c.fail("cage.loops[" + std::to_string(k) + "]", "needs at least 3 vertices");
        // The outer loop counter-clockwise, holes clockwise (cage.h); keyframe
        // coefficients follow their vertices (to_full_layout).
        if ((signed_area(cage.loops[k]) > 0) != (k == 0)) {
          std::reverse(cage.loops[k].begin(), cage.loops[k].end());
          reversed[k] = true;
        }
      }
      try {
        check_cage(s.shape, cage);
      } catch (const InputError& e) {
        c.fail("cage", e.what());
      }
      s.cage = std::move(cage);
    }
  }
  if (const json* v = field(j, "samples")) {
    if (!v->is_number_integer() || v->get<long long>() < kMinSamples || v->get<long long>() > kMaxSamples)
      c.fail("samples", "expected an integer between 100 and 10,000,000");
    s.samples = v->get<int>();
  }
  if (const json* v = field(j, "hessian_ratio")) {
    s.hessian_ratio = number(c, *v, "hessian_ratio");
    if (!(s.hessian_ratio > 0 && s.hessian_ratio <= 1)) c.fail("hessian_ratio", "must lie in (0, 1]");
  }
  if (const json* v = field(j, "handles")) s.handles = points(c, *v, "handles");
  for (size_t i = 0; i < s.handles.size(); ++i)
    if (const std::string why = off_shape_reason(s.shape, s.handles[i]); !why.empty()) c.fail("handles[" + std::to_string(i) + "]", why);
  if (const json* kfs = field(j, "keyframes")) {
    if (!kfs->is_array()) c.fail("keyframes", "expected an array");
    const int full = s.cage ? basis_size(*s.cage) : -1;
    for (size_t k = 0; k < kfs->size(); ++k) {
      const std::string p = "keyframes[" + std::to_string(k) + "]";
      const json& kf = (*kfs)[k];
      if (!kf.is_object()) c.fail(p, "expected an object");
      check_keys(c, kf, p, {"time", "targets", "layout", "phi", "psi", "timing", "start"});
      Keyframe key;
      const json* t = field(kf, "time");
      if (!t) c.fail(p, "missing \"time\"");
      key.time = number(c, *t, p + ".time");
      if (!s.keyframes.empty() && key.time <= s.keyframes.back().time)
        c.fail(p + ".time", "keyframe times must increase (previous keyframe is at " + std::to_string(s.keyframes.back().time) + ")");
      if (const json* tg = field(kf, "targets")) {
        key.targets = points(c, *tg, p + ".targets");
        if (key.targets.size() != s.handles.size())
          c.fail(p + ".targets", "has " + std::to_string(key.targets.size()) + " targets; the scene has " +
                                     std::to_string(s.handles.size()) + " handles");
      }
      const json* phi = field(kf, "phi");
      const json* psi = field(kf, "psi");
      Layout layout = Layout::Full;
      if (const json* l = field(kf, "layout")) {
        if (!l->is_string() || (*l != "full" && *l != "reduced"))
          c.fail(p + ".layout", "expected \"full\" or \"reduced\", got " + (l->is_string() ? "\"" + l->get<std::string>() + "\"" : type_name(*l)));
        if (!phi && !psi) c.fail(p + ".layout", "describes coefficients \"phi\" and \"psi\", which this keyframe does not give");
        layout = *l == "reduced" ? Layout::Reduced : Layout::Full;
      }
      if (phi || psi) {
        if (!phi || !psi) c.fail(p, "coefficients need both \"phi\" and \"psi\"");
        HarmonicMap m{coefficients(c, *phi, p + ".phi"), coefficients(c, *psi, p + ".psi")};
        if (m.phi.size() != m.psi.size()) c.fail(p, "\"phi\" and \"psi\" differ in length");
        if (full < 0) c.fail(p, "coefficients need the scene's cage (\"cage\": {\"loops\", \"hole_points\"}) to be given");
        const int reduced = MapSpace(file_cage, Gauge::Map).n();
        const int want = layout == Layout::Full ? full : reduced;
        if (m.phi.size() != want) {
          const std::string counts = std::to_string(full) + " in the full layout (every cage vertex, then one per hole) or " +
                                     std::to_string(reduced) +
                                     " in the reduced layout (\"layout\": \"reduced\": each hole loop without its first two "
                                     "vertices, then one per hole)";
          const bool looks_reduced = layout == Layout::Full && m.phi.size() == reduced && reduced != full;
          c.fail(p + ".phi", "has " + std::to_string(m.phi.size()) + " coefficients" +
                                 (layout == Layout::Reduced ? " in the reduced layout" : "") + "; the cage needs " + counts +
                                 (looks_reduced ? "; for the reduced layout add \"layout\": \"reduced\" to the keyframe" : ""));
        }
        m.phi = to_full_layout(m.phi, layout, file_cage, reversed);
        m.psi = to_full_layout(m.psi, layout, file_cage, reversed);
        key.coefficients = std::move(m);
      }
      if (const json* tm = field(kf, "timing")) {
        if (file_version < 2) c.fail(p + ".timing", "keyframe timing needs \"hsi_scene\": 2 (this file says version 1)");
        if (!tm->is_string()) c.fail(p + ".timing", "expected a string (" + std::string(kKeyTimingNames) + "), got " + type_name(*tm));
        const auto timing = parse_key_timing(tm->get<std::string>());
        if (!timing) c.fail(p + ".timing", "unknown timing \"" + tm->get<std::string>() + "\" (expected one of: " + kKeyTimingNames + ")");
        key.timing = *timing;
      }
      if (const json* st = field(kf, "start")) {
        if (file_version < 2) c.fail(p + ".start", "a keyframe's \"start\" needs \"hsi_scene\": 2 (this file says version 1)");
        if (!st->is_string() || (*st != "previous" && *st != "rest"))
          c.fail(p + ".start", "expected \"previous\" or \"rest\", got " + (st->is_string() ? "\"" + st->get<std::string>() + "\"" : type_name(*st)));
        if (key.targets.empty()) c.fail(p + ".start", "says where authoring from targets starts; this keyframe gives no \"targets\"");
        key.start = *st == "rest" ? Keyframe::Start::Rest : Keyframe::Start::Previous;
      }
      if (key.targets.empty() && !key.coefficients && !s.handles.empty())
        c.fail(p, "needs \"targets\" (one per handle) or coefficients \"phi\"/\"psi\"");
      s.keyframes.push_back(std::move(key));
    }
  }
  return s;
}

void rethrow_in_scene(const Scene& scene, const InputError& error) {
  const std::string what = error.what();
  if (scene.source.empty() || what.rfind(scene.source + ": ", 0) == 0) throw error;
  throw InputError(scene.source + ": " + what);
}

Scene load_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": read error");
  return parse_scene(ss.str(), path.parent_path(), path.string());
}

std::string scene_to_json(const Scene& s) {
  json j;
  // Version 1 where nothing needs 2 (keyframe timing, a keyframe's start), so such files keep it.
  const bool v2 = std::any_of(s.keyframes.begin(), s.keyframes.end(),
                              [](const Keyframe& k) { return k.timing != KeyTiming::Linear || k.start != Keyframe::Start::Previous; });
  j["hsi_scene"] = v2 ? kSceneVersion : 1;
  if (!s.name.empty()) j["name"] = s.name;
  j["shape"]["outer"] = to_json(s.shape.outer);
  j["shape"]["holes"] = json::array();
  for (const Loop& h : s.shape.holes) j["shape"]["holes"].push_back(to_json(h));
  if (!s.texture.empty()) j["texture"] = s.texture.generic_string();
  if (s.texture_rect) j["texture_rect"] = *s.texture_rect;
  if (s.texture_filter != TextureFilter::Linear) j["texture_filter"] = texture_filter_name(s.texture_filter);
  j["cage"]["clearance"] = s.cage_options.clearance;
  j["cage"]["max_vertices_per_loop"] = s.cage_options.max_vertices_per_loop;
  if (s.cage) {
    j["cage"]["loops"] = json::array();
    for (const Loop& l : s.cage->loops) j["cage"]["loops"].push_back(to_json(l));
    j["cage"]["hole_points"] = to_json(s.cage->hole_points);
  }
  j["samples"] = s.samples;
  j["hessian_ratio"] = s.hessian_ratio;
  if (!s.handles.empty()) j["handles"] = to_json(s.handles);
  if (!s.keyframes.empty()) {
    j["keyframes"] = json::array();
    for (const Keyframe& k : s.keyframes) {
      json kj;
      kj["time"] = k.time;
      if (!k.targets.empty()) kj["targets"] = to_json(k.targets);
      if (k.coefficients) {
        kj["phi"] = to_json(k.coefficients->phi);
        kj["psi"] = to_json(k.coefficients->psi);
      }
      if (k.timing != KeyTiming::Linear) kj["timing"] = to_string(k.timing);
      if (k.start == Keyframe::Start::Rest) kj["start"] = "rest";
      j["keyframes"].push_back(kj);
    }
  }
  return j.dump(1) + "\n";
}

void save_scene(const Scene& scene, const std::filesystem::path& path) { write_file_atomic(path, scene_to_json(scene)); }

Cage scene_cage(const Scene& scene) {
  if (scene.cage) return *scene.cage;
  try {
    return build_cage(scene.shape, scene.cage_options);
  } catch (const InputError& e) {
    rethrow_in_scene(scene, e);
  }
}

}  // namespace hsi
