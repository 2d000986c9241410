// The viewer application: state, UI (Dear ImGui), playback, editing, scripts.
#include "app.h"

#include <imgui.h>
#include <volk.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "hsi/basis.h"
#include "hsi/compute/renderer.h"
#include "hsi/scene_texture.h"
#include "hsi/keyframes.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/triangulate.h"
#include "presenter.h"
#include "solver.h"

namespace hsi::viewer {

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kInf = std::numeric_limits<double>::infinity();

// What an undo step restores: everything editing changes.
struct EditState {
  std::vector<cd> handles;
  std::vector<Keyframe> keyframes;
};

struct ScriptStep {
  std::string op;
  std::vector<std::string> args;
  int line = 0;
};

std::vector<ScriptStep> parse_script(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("--script: cannot read " + path);
  std::vector<ScriptStep> steps;
  std::string line;
  int n = 0;
  static const std::vector<std::pair<std::string, size_t>> known = {
      {"play", 0},   {"pause", 0}, {"frames", 1}, {"seek", 1},       {"key", 1},        {"drag", 3},  {"add-handle", 2},
      {"remove-handle", 1}, {"undo", 0}, {"redo", 0}, {"save", 1}, {"screenshot", 1}, {"exit", 0}, {"expect-certified", 0}};
  while (std::getline(in, line)) {
    ++n;
    if (const size_t c = line.find('#'); c != std::string::npos) line.resize(c);
    std::istringstream ss(line);
    ScriptStep s;
    s.line = n;
    if (!(ss >> s.op)) continue;
    for (std::string a; ss >> a;) s.args.push_back(a);
    const auto it = std::find_if(known.begin(), known.end(), [&](const auto& k) { return k.first == s.op; });
    if (it == known.end()) throw InputError(path + ":" + std::to_string(n) + ": unknown script command '" + s.op + "'");
    if (s.args.size() != it->second)
      throw InputError(path + ":" + std::to_string(n) + ": '" + s.op + "' takes " + std::to_string(it->second) + " argument(s)");
    steps.push_back(std::move(s));
  }
  return steps;
}

double number(const ScriptStep& s, size_t i) {
  try {
    size_t used = 0;
    const double v = std::stod(s.args[i], &used);
    if (used == s.args[i].size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw InputError("script line " + std::to_string(s.line) + ": '" + s.args[i] + "' is not a number");
}

ImU32 rgba(float r, float g, float b, float a = 1) { return ImGui::ColorConvertFloat4ToU32(ImVec4(r, g, b, a)); }

class App {
 public:
  App(const Options& o, GLFWwindow* window, compute::Context& ctx);
  ~App();
  bool frame();  // one UI frame; false: quit
  int script_status() const { return script_failed_ ? 4 : 0; }

 private:
  // --- scene and editing ---
  void load();
  void keyframes_changed();  // pushes the keyframes to the solver, recomputes the view box
  void push_undo();
  void restore(const EditState& s);
  EditState snapshot() const { return {scene_.handles, scene_.keyframes}; }
  int keyframe_at_frame(int frame) const;  // −1 if the frame is no keyframe's
  void add_keyframe();
  void remove_keyframe();
  void add_handle_at(cd world);
  void remove_handle(int k);
  void begin_drag(int handle, int key);
  void drag_to(cd world);
  void end_drag();
  void poll_pose_results();
  bool save(const std::string& path);
  void message(const std::string& m, bool error = false);

  // --- display ---
  const HarmonicMap* shown_map(bool* certified, std::string* reason, bool* is_key);
  // Whether a map's boundary image crosses itself (hsi/overlap.h), cached by its coefficients.
  const OverlapResult& overlap_of(const HarmonicMap& map);
  void layout();
  void update_renderer_and_render();
  cd to_world(ImVec2 screen) const;
  ImVec2 to_screen(cd world) const;
  std::optional<cd> rest_point_at(const HarmonicMap& map, cd world);
  void handle_input();
  void handle_keys();
  void draw_viewport_overlays();
  void draw_side_panel();
  void draw_timeline();
  void draw_help();
  void step(int delta);
  void toggle_play();
  void run_script();

  Options o_;
  GLFWwindow* window_;
  compute::Context& ctx_;
  Scene scene_;
  std::string scene_path_;
  std::shared_ptr<const ShapeSetup> setup_;
  OverlapResult overlap_;           // of the map with coefficients overlap_phi_, overlap_psi_
  VectorXcd overlap_phi_, overlap_psi_;
  std::unique_ptr<Solver> solver_;
  std::unique_ptr<Presenter> presenter_;
  std::unique_ptr<compute::Renderer> renderer_;
  TriMesh mesh_, pick_mesh_;
  BasisRows pick_rows_, probe_rows_;
  RgbaImage texture_;
  std::array<double, 4> texture_rect_{};
  std::vector<EditState> undo_, redo_;
  bool dirty_ = false, title_dirty_ = false;

  // view
  float scale_ = 1;  // content scale (high DPI)
  ImVec2 vp_pos_{0, 0}, vp_size_{1, 1};  // viewport in window points
  ImVec2 fb_scale_{1, 1};
  BoundingBox box_{};
  double zoom_ = 1;
  cd pan_{0, 0};
  compute::View view_;
  double dist_hi_ = 2;
  uint32_t overlays_ = 0;
  bool show_cage_ = false, show_handles_ = true, show_status_ = true, show_help_ = false;

  // playback
  int cur_ = 0;
  bool playing_ = false, loop_ = true;
  double speed_ = 1, acc_ = 0;
  int shown_index_ = -1;
  std::shared_ptr<const SolvedFrame> shown_;
  Clock::time_point last_time_ = Clock::now();
  std::vector<Clock::time_point> advance_times_;  // for the playback rate
  double render_ms_ = 0;

  // rendering cache
  const void* rendered_map_ = nullptr;
  uint64_t rendered_sig_ = 0;
  bool frame_ready_ = false;  // the presenter holds the image of the current state

  // editing
  int hover_handle_ = -1;
  struct Drag {
    bool active = false, releasing = false;
    int handle = -1, key = -1;
    std::vector<cd> targets;
    HarmonicMap latest;
    bool has_latest = false;
    uint64_t final_id = 0;
    EditState before;
    std::string status;
  } drag_;
  uint64_t pose_id_ = 0;
  std::string message_;
  bool message_error_ = false;
  Clock::time_point message_time_;
  std::optional<HarmonicMap> pick_map_;  // the map pick_f_ belongs to
  VectorXcd pick_f_;
  bool middle_drag_ = false;

  // script
  std::vector<ScriptStep> script_;
  size_t script_pc_ = 0;
  int script_wait_ = 0, script_wait_start_ = 0;
  int played_frames_ = 0;
  bool script_failed_ = false, quit_ = false;
  bool capture_next_ = false;
  std::string capture_path_;
};

App::App(const Options& o, GLFWwindow* window, compute::Context& ctx) : o_(o), window_(window), ctx_(ctx) {
  loop_ = o.loop;
  speed_ = o.speed;
  for (std::stringstream ss(o.overlays); ss.good();) {
    std::string s;
    std::getline(ss, s, ',');
    if (s == "distortion") overlays_ |= compute::kOverlayDistortion;
    else if (s == "boundary") overlays_ |= compute::kOverlayBoundary;
    else if (s == "cage") show_cage_ = true;
    else if (s == "handles") show_handles_ = true;
    else if (s == "status") show_status_ = true;
    else if (s == "help") show_help_ = true;
    else if (s != "none" && !s.empty())
      throw InputError("--overlays: unknown overlay '" + s + "' (distortion, boundary, cage, handles, status, help, none)");
  }
  if (o.overlays.find("handles") == std::string::npos) show_handles_ = false;
  if (o.overlays.find("status") == std::string::npos) show_status_ = false;
  if (!o.script.empty()) script_ = parse_script(o.script);
  if (o.screenshot_after >= 0) {
    script_.push_back({"play", {}, 0});
    script_.push_back({"frames", {std::to_string(o.screenshot_after)}, 0});
    script_.push_back({"pause", {}, 0});
    if (!o.screenshot.empty()) script_.push_back({"screenshot", {o.screenshot}, 0});
    if (o.exit_after) script_.push_back({"exit", {}, 0});
  } else if (!o.screenshot.empty()) {
    script_.push_back({"screenshot", {o.screenshot}, 0});
    if (o.exit_after) script_.push_back({"exit", {}, 0});
  } else if (o.exit_after) {
    script_.push_back({"exit", {}, 0});
  }
  if (!script_.empty()) o_.lockstep = true;

  float xs = 1, ys = 1;
  glfwGetWindowContentScale(window_, &xs, &ys);
  scale_ = std::max(1.0f, std::max(xs, ys));

  load();
  presenter_ = std::make_unique<Presenter>(ctx_, window_, o.vsync);

  // Fonts: DejaVu Sans (Latin, Greek for σ, arrows) at the content scale.
  ImGuiIO& io = ImGui::GetIO();
  static const ImWchar ranges[] = {0x0020, 0x00FF, 0x0370, 0x03FF, 0x2000, 0x206F, 0x2070, 0x209F,
                                   0x2190, 0x21FF, 0x2200, 0x22FF, 0x25A0, 0x25FF, 0x2700, 0x27BF, 0};
  const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  if (std::filesystem::exists(font)) {
    io.Fonts->AddFontFromFileTTF(font, std::round(15.0f * scale_), nullptr, ranges);
  } else {
    ImFontConfig cfg;
    cfg.SizePixels = std::round(13.0f * scale_);
    io.Fonts->AddFontDefault(&cfg);
  }
  ImGui::GetStyle().ScaleAllSizes(scale_);
  presenter_->upload_fonts();
  playing_ = o.play && solver_->frame_count() > 1;
  if (!script_.empty()) playing_ = false;  // the script says when to play
}

App::~App() {
  if (presenter_) presenter_->wait_idle();
  solver_.reset();
  renderer_.reset();
  presenter_.reset();
}

void App::load() {
  scene_path_ = o_.scene;
  scene_ = load_scene(o_.scene);
  if (scene_.keyframes.empty()) {  // a bare shape: one keyframe, the identity
    Keyframe k;
    k.time = 0;
    scene_.keyframes.push_back(k);
  }
  // Coefficients are stored over a cage: keep the one they were made with.
  if (!scene_.cage) scene_.cage = build_cage(scene_.shape, scene_.cage_options);
  setup_ = scene_setup(scene_, o_.samples);
  for (Keyframe& k : scene_.keyframes)
    if (!k.coefficients && k.targets.empty()) k.coefficients = identity_map(setup_->cage);
  std::printf("hsi-viewer: %s: certifying / solving %zu keyframe(s)\n", o_.scene.c_str(), scene_.keyframes.size());
  std::fflush(stdout);
  solve_scene_keyframes(scene_, *setup_);

  if (o_.backend != "auto" && o_.backend != "cpu" && o_.backend != "cuda")
    throw InputError("--backend: '" + o_.backend + "' is not auto, cpu or cuda");
#ifndef HSI_WITH_CUDA
  if (o_.backend == "cuda") throw InputError("--backend cuda: this hsi-viewer was built without CUDA");
#endif
  solver_ = std::make_unique<Solver>(setup_, o_.rate, o_.backend != "cpu");
  if (o_.backend == "cuda" && std::string(solver_->backend()).find("CUDA") == std::string::npos &&
      std::string(solver_->backend()).find("cuda") == std::string::npos)
    throw InputError("--backend cuda: no CUDA device");

  // Texture (or a checkerboard), render mesh, picking mesh and probe points.
  {
    SceneTexture st = scene_texture(scene_, o_.scene, false, false);
    texture_ = std::move(st.image);
    texture_rect_ = st.rect;
  }
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(scene_.shape, o_.mesh_vertices);
  mesh_ = triangulate(scene_.shape, to);
  to.max_edge = edge_for_vertex_count(scene_.shape, 3000);
  pick_mesh_ = triangulate(scene_.shape, to);
  pick_rows_ = evaluate_basis(setup_->cage, pick_mesh_.vertices, kBasisC);
  std::vector<cd> probe;
  for (int v = 0; v < mesh_.vertex_count(); ++v)
    if (mesh_.boundary_loop[static_cast<size_t>(v)] >= 0) probe.push_back(mesh_.vertices[static_cast<size_t>(v)]);
  probe_rows_ = evaluate_basis(setup_->cage, probe, kBasisC | kBasisD);
  keyframes_changed();
}

void App::keyframes_changed() {
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : scene_.keyframes) {
    times.push_back(k.time);
    maps.push_back(*k.coefficients);
  }
  solver_->set_keyframes(times, maps);
  // The view frames every keyframe's image (so playback does not jump); the colour
  // map spans the keyframes' largest distortion.
  box_ = {cd(kInf, kInf), cd(-kInf, -kInf)};
  double kappa = 1;
  for (const HarmonicMap& m : maps) {
    const MapValues v = evaluate_map(probe_rows_, m);
    for (Eigen::Index i = 0; i < v.f.size(); ++i) {
      const cd z = v.f(i);
      box_.lo = {std::min(box_.lo.real(), z.real()), std::min(box_.lo.imag(), z.imag())};
      box_.hi = {std::max(box_.hi.real(), z.real()), std::max(box_.hi.imag(), z.imag())};
      const double a = std::abs(v.f_z(i)), b = std::abs(v.fzbar_conj(i));
      if (a > b) kappa = std::max(kappa, (a + b) / (a - b));
    }
  }
  // Some room around it: poses between keyframes may reach a little further.
  const cd pad = 0.06 * (box_.hi - box_.lo);
  box_.lo -= cd(pad.real(), pad.imag());
  box_.hi += cd(pad.real(), pad.imag());
  dist_hi_ = compute::round_distortion_hi(std::max(kappa * 1.1, 1.2));
  cur_ = std::clamp(cur_, 0, solver_->frame_count() - 1);
  shown_.reset();
  shown_index_ = -1;
  rendered_map_ = nullptr;
  pick_map_.reset();
}

void App::message(const std::string& m, bool error) {
  message_ = m;
  message_error_ = error;
  message_time_ = Clock::now();
  std::printf("hsi-viewer: %s\n", m.c_str());
  std::fflush(stdout);
}

void App::push_undo() {
  undo_.push_back(snapshot());
  if (undo_.size() > 200) undo_.erase(undo_.begin());
  redo_.clear();
  dirty_ = true;
}

void App::restore(const EditState& s) {
  scene_.handles = s.handles;
  scene_.keyframes = s.keyframes;
  dirty_ = true;
  keyframes_changed();
}

int App::keyframe_at_frame(int frame) const {
  for (size_t k = 0; k < scene_.keyframes.size(); ++k)
    if (solver_->frame_at(scene_.keyframes[k].time) == frame) return static_cast<int>(k);
  return -1;
}

// The map on screen: a drag's latest certified pose, the keyframe itself at a
// keyframe's frame, else the solved frame (or the last one shown while it solves).
const HarmonicMap* App::shown_map(bool* certified, std::string* reason, bool* is_key) {
  *certified = true;
  *is_key = false;
  reason->clear();
  if (drag_.active && drag_.has_latest) {
    *is_key = true;
    return &drag_.latest;
  }
  const int key = keyframe_at_frame(cur_);
  if (key >= 0) {
    *is_key = true;
    shown_index_ = cur_;
    return &*scene_.keyframes[static_cast<size_t>(key)].coefficients;
  }
  if (auto f = solver_->get(cur_)) {
    shown_ = f;
    shown_index_ = cur_;
  }
  if (!shown_) {
    *certified = true;
    return &*scene_.keyframes.front().coefficients;
  }
  *certified = shown_->certified;
  *reason = shown_->message;
  return &shown_->map;
}

const OverlapResult& App::overlap_of(const HarmonicMap& map) {
  if (overlap_phi_.size() != map.phi.size() || overlap_phi_ != map.phi || overlap_psi_ != map.psi) {
    overlap_ = setup_->overlap.check(map);
    overlap_phi_ = map.phi;
    overlap_psi_ = map.psi;
  }
  return overlap_;
}

void App::step(int delta) {
  playing_ = false;
  const int n = solver_->frame_count();
  cur_ = loop_ ? ((cur_ + delta) % n + n) % n : std::clamp(cur_ + delta, 0, n - 1);
}

void App::toggle_play() {
  if (solver_->frame_count() < 2) return;
  playing_ = !playing_;
  if (playing_ && !loop_ && cur_ >= solver_->frame_count() - 1) cur_ = 0;
  acc_ = 0;
}

void App::add_keyframe() {
  const int key = keyframe_at_frame(cur_);
  if (drag_.active) return;
  if (key >= 0 && key + 1 < static_cast<int>(scene_.keyframes.size())) {
    message("frame " + std::to_string(cur_) + " is keyframe " + std::to_string(key) +
            " already: drag its handles to pose it, or add a keyframe between keyframes");
    return;
  }
  Keyframe k;
  if (key >= 0) {  // at the last keyframe: a new keyframe one time unit later, posed like it
    k = scene_.keyframes.back();
    k.time = scene_.keyframes.back().time + 1.0;
  } else {
    const auto f = solver_->get(cur_);
    if (!f) {
      message("frame " + std::to_string(cur_) + " is still being solved: add the keyframe when it is shown", true);
      return;
    }
    if (!f->certified) {
      message("frame " + std::to_string(cur_) + " is not certified: it cannot become a keyframe", true);
      return;
    }
    k.time = solver_->time_of(cur_);
    k.coefficients = f->map;
    k.targets = map_points(setup_->cage, f->map, scene_.handles);
  }
  push_undo();
  const auto at = std::upper_bound(scene_.keyframes.begin(), scene_.keyframes.end(), k.time,
                                   [](double t, const Keyframe& x) { return t < x.time; });
  const int index = static_cast<int>(at - scene_.keyframes.begin());
  scene_.keyframes.insert(at, k);
  keyframes_changed();
  cur_ = solver_->frame_at(k.time);
  playing_ = false;
  message("added keyframe " + std::to_string(index) + " at t = " + std::to_string(k.time));
}

void App::remove_keyframe() {
  const int key = keyframe_at_frame(cur_);
  if (key < 0 || drag_.active) {
    message("the current frame is not a keyframe: step to one (the timeline's marks) to remove it");
    return;
  }
  if (scene_.keyframes.size() <= 1) {
    message("the last keyframe cannot be removed", true);
    return;
  }
  push_undo();
  scene_.keyframes.erase(scene_.keyframes.begin() + key);
  keyframes_changed();
  message("removed keyframe " + std::to_string(key));
}

// The rest point that the map sends to `world`: the pick mesh's triangle whose image
// holds it (the map is injective), barycentric in the image, mapped back.
std::optional<cd> App::rest_point_at(const HarmonicMap& map, cd world) {
  if (!pick_map_ || pick_map_->phi.size() != map.phi.size() || pick_map_->phi != map.phi || pick_map_->psi != map.psi) {
    pick_f_ = evaluate_map(pick_rows_, map).f;
    pick_map_ = map;
  }
  for (const auto& t : pick_mesh_.triangles) {
    const cd a = pick_f_(t[0]), b = pick_f_(t[1]), c = pick_f_(t[2]);
    const double det = (b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real();
    if (std::abs(det) < 1e-300) continue;
    const cd p = world - a;
    const double u = (p.real() * (c - a).imag() - p.imag() * (c - a).real()) / det;
    const double v = ((b - a).real() * p.imag() - (b - a).imag() * p.real()) / det;
    if (u >= -1e-9 && v >= -1e-9 && u + v <= 1 + 1e-9) {
      const auto& V = pick_mesh_.vertices;
      return V[static_cast<size_t>(t[0])] + u * (V[static_cast<size_t>(t[1])] - V[static_cast<size_t>(t[0])]) +
             v * (V[static_cast<size_t>(t[2])] - V[static_cast<size_t>(t[0])]);
    }
  }
  return std::nullopt;
}

void App::add_handle_at(cd world) {
  bool cert = true, is_key = false;
  std::string reason;
  const HarmonicMap* m = shown_map(&cert, &reason, &is_key);
  const std::optional<cd> rest = rest_point_at(*m, world);
  if (!rest) {
    message("no handle added: click on the shape");
    return;
  }
  push_undo();
  scene_.handles.push_back(*rest);
  for (Keyframe& k : scene_.keyframes) {  // every keyframe keeps its pose: the handle's target is where it is
    const cd q = map_points(setup_->cage, *k.coefficients, std::span<const cd>(&*rest, 1))[0];
    if (k.targets.size() + 1 == scene_.handles.size()) k.targets.push_back(q);
    else k.targets = map_points(setup_->cage, *k.coefficients, scene_.handles);
  }
  char where[96];
  std::snprintf(where, sizeof where, " at rest point (%.3f, %.3f)", rest->real(), rest->imag());
  message("added handle " + std::to_string(scene_.handles.size() - 1) + where);
}

void App::remove_handle(int h) {
  if (h < 0 || h >= static_cast<int>(scene_.handles.size())) return;
  push_undo();
  scene_.handles.erase(scene_.handles.begin() + h);
  for (Keyframe& k : scene_.keyframes)
    if (k.targets.size() == scene_.handles.size() + 1) k.targets.erase(k.targets.begin() + h);
  hover_handle_ = -1;
  message("removed handle " + std::to_string(h));
}

void App::begin_drag(int handle, int key) {
  drag_ = Drag();
  drag_.active = true;
  drag_.handle = handle;
  drag_.key = key;
  drag_.before = snapshot();
  drag_.latest = *scene_.keyframes[static_cast<size_t>(key)].coefficients;
  drag_.has_latest = true;
  // Every other handle stays where this keyframe has it.
  drag_.targets = map_points(setup_->cage, drag_.latest, scene_.handles);
  playing_ = false;
}

void App::drag_to(cd world) {
  if (!drag_.active || drag_.releasing) return;
  if (std::abs(world - drag_.targets[static_cast<size_t>(drag_.handle)]) < 1e-12) return;
  drag_.targets[static_cast<size_t>(drag_.handle)] = world;
  PoseRequest r;
  r.id = ++pose_id_;
  r.keyframe = drag_.key;
  r.handles = scene_.handles;
  r.targets = drag_.targets;
  r.start = drag_.latest;
  solver_->pose(std::move(r));
}

void App::end_drag() {
  if (!drag_.active || drag_.releasing) return;
  drag_.releasing = true;
  PoseRequest r;
  r.id = ++pose_id_;
  r.keyframe = drag_.key;
  r.handles = scene_.handles;
  r.targets = drag_.targets;
  r.start = drag_.latest;
  r.final = true;
  drag_.final_id = r.id;
  solver_->pose(std::move(r));
}

void App::poll_pose_results() {
  while (auto res = solver_->take_pose_result()) {
    if (!drag_.active) continue;
    if (!res->error.empty()) {
      message("pose: " + res->error, true);
      if (res->id == drag_.final_id) drag_ = Drag();
      continue;
    }
    if (res->result.certified) {  // always, unless the start was not: never show a folding map
      drag_.latest = res->result.map;
      drag_.has_latest = true;
    }
    drag_.status = res->result.message;
    if (res->id == drag_.final_id) {
      const EditState before = drag_.before;
      undo_.push_back(before);
      redo_.clear();
      dirty_ = true;
      Keyframe& k = scene_.keyframes[static_cast<size_t>(drag_.key)];
      k.coefficients = drag_.latest;
      k.targets = res->targets;
      const std::string status = res->result.message;
      const int key = drag_.key;
      drag_ = Drag();
      keyframes_changed();
      message("keyframe " + std::to_string(key) + ": " + status, !res->result.reached);
    }
  }
}

bool App::save(const std::string& path) {
  try {
    Scene out = scene_;
    const std::filesystem::path p(path);
    if (p.parent_path() != std::filesystem::path(scene_path_).parent_path() && !out.texture.empty() &&
        out.texture.is_relative())
      out.texture = std::filesystem::relative(scene_.texture_path(), p.parent_path().empty() ? "." : p.parent_path());
    save_scene(out, p);
    if (path == (o_.output.empty() ? o_.scene : o_.output)) dirty_ = false;
    keyframes_changed();
    message("saved " + path);
    return true;
  } catch (const std::exception& e) {
    message(std::string("could not save: ") + e.what(), true);
    return false;
  }
}

// --- layout, rendering ----------------------------------------------------------------

void App::layout() {
  ImGuiIO& io = ImGui::GetIO();
  const float side = std::min(340.0f * scale_, 0.4f * io.DisplaySize.x);
  const float bottom = std::min(ImGui::GetFrameHeightWithSpacing() * 2 + ImGui::GetStyle().WindowPadding.y * 2 + 8 * scale_,
                                0.4f * io.DisplaySize.y);
  vp_pos_ = ImVec2(0, 0);
  vp_size_ = ImVec2(std::max(1.0f, io.DisplaySize.x - side), std::max(1.0f, io.DisplaySize.y - bottom));
  fb_scale_ = io.DisplayFramebufferScale;
}

void App::update_renderer_and_render() {
  const int w = std::max(16, static_cast<int>(std::lround(vp_size_.x * fb_scale_.x)));
  const int h = std::max(16, static_cast<int>(std::lround(vp_size_.y * fb_scale_.y)));
  if (!renderer_ || renderer_->width() != w || renderer_->height() != h) {
    presenter_->wait_idle();
    renderer_.reset();
    renderer_ = std::make_unique<compute::Renderer>(ctx_, w, h);
    renderer_->set_mesh(mesh_, scene_.handles);
    renderer_->set_texture(texture_, texture_rect_);
    rendered_map_ = nullptr;
  }
  view_ = compute::View::fit(box_, w, h, 16.0 * scale_ * fb_scale_.x);
  view_.pixels_per_unit *= zoom_;
  view_.world_center += pan_;

  bool certified = true, is_key = false;
  std::string reason;
  const HarmonicMap* map = shown_map(&certified, &reason, &is_key);
  // A signature of everything the image depends on besides the map's address.
  uint64_t sig = overlays_ * 1315423911ull ^ static_cast<uint64_t>(certified) * 2654435761ull;
  auto mix = [&](double v) {
    uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    sig = (sig ^ b) * 1099511628211ull;
  };
  mix(view_.pixels_per_unit);
  mix(view_.world_center.real());
  mix(view_.world_center.imag());
  mix(dist_hi_);
  mix(static_cast<double>(w));
  mix(static_cast<double>(h));
  for (Eigen::Index i = 0; i < map->phi.size(); ++i) {
    mix(map->phi(i).real());
    mix(map->phi(i).imag());
    mix(map->psi(i).real());
    mix(map->psi(i).imag());
  }
  if (rendered_map_ && sig == rendered_sig_) return;
  compute::RenderStyle style;
  style.overlays = overlays_ & (compute::kOverlayDistortion | compute::kOverlayBoundary);
  style.background = {0.97f, 0.97f, 0.98f, 1};
  style.distortion_lo = 1;
  style.distortion_hi = dist_hi_;
  style.boundary_width_px = std::max(1.5f, 1.5f * scale_ * fb_scale_.x);
  style.uncertified = !certified;
  const auto t0 = Clock::now();
  presenter_->set_frame_image(renderer_->render(setup_->cage, *map, view_, style));
  render_ms_ = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  rendered_map_ = map;
  rendered_sig_ = sig;
}

cd App::to_world(ImVec2 s) const {
  const double px = (s.x - vp_pos_.x) * fb_scale_.x, py = (s.y - vp_pos_.y) * fb_scale_.y;
  return {view_.world_center.real() + (px - view_.pixel_center.real()) / view_.pixels_per_unit,
          view_.world_center.imag() - (py - view_.pixel_center.imag()) / view_.pixels_per_unit};
}

ImVec2 App::to_screen(cd w) const {
  const cd p = view_.to_pixel(w);
  return {vp_pos_.x + static_cast<float>(p.real() / fb_scale_.x), vp_pos_.y + static_cast<float>(p.imag() / fb_scale_.y)};
}

// --- input -----------------------------------------------------------------------------

void App::handle_keys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  auto pressed = [](int key) { return ImGui::IsKeyPressed(key, false); };
  auto repeated = [](int key) { return ImGui::IsKeyPressed(key, true); };
  const bool ctrl = io.KeyCtrl;
  if (ctrl) {
    if (pressed(GLFW_KEY_Z) && !io.KeyShift) {
      if (!undo_.empty() && !drag_.active) {
        redo_.push_back(snapshot());
        restore(undo_.back());
        undo_.pop_back();
        message("undo");
      }
    } else if (pressed(GLFW_KEY_Y) || (pressed(GLFW_KEY_Z) && io.KeyShift)) {
      if (!redo_.empty() && !drag_.active) {
        undo_.push_back(snapshot());
        restore(redo_.back());
        redo_.pop_back();
        message("redo");
      }
    } else if (pressed(GLFW_KEY_S)) {
      save(o_.output.empty() ? o_.scene : o_.output);
    } else if (pressed(GLFW_KEY_Q)) {
      quit_ = true;
    }
    return;
  }
  if (pressed(GLFW_KEY_SPACE)) toggle_play();
  if (repeated(GLFW_KEY_RIGHT) || repeated(GLFW_KEY_PERIOD)) step(+1);
  if (repeated(GLFW_KEY_LEFT) || repeated(GLFW_KEY_COMMA)) step(-1);
  if (pressed(GLFW_KEY_HOME)) {
    playing_ = false;
    cur_ = 0;
  }
  if (pressed(GLFW_KEY_END)) {
    playing_ = false;
    cur_ = solver_->frame_count() - 1;
  }
  if (pressed(GLFW_KEY_PAGE_UP) || pressed(GLFW_KEY_PAGE_DOWN)) {  // previous / next keyframe
    playing_ = false;
    const bool next = pressed(GLFW_KEY_PAGE_DOWN);
    int best = next ? solver_->frame_count() - 1 : 0;
    for (const Keyframe& k : scene_.keyframes) {
      const int f = solver_->frame_at(k.time);
      if (next && f > cur_) best = std::min(best, f);
      if (!next && f < cur_) best = std::max(best, f);
    }
    cur_ = best;
  }
  if (pressed(GLFW_KEY_L)) loop_ = !loop_;
  if (pressed(GLFW_KEY_LEFT_BRACKET)) speed_ = std::max(0.125, speed_ / 2);
  if (pressed(GLFW_KEY_RIGHT_BRACKET)) speed_ = std::min(8.0, speed_ * 2);
  if (pressed(GLFW_KEY_D)) overlays_ ^= compute::kOverlayDistortion;
  if (pressed(GLFW_KEY_B)) overlays_ ^= compute::kOverlayBoundary;
  if (pressed(GLFW_KEY_C)) show_cage_ = !show_cage_;
  if (pressed(GLFW_KEY_P)) show_handles_ = !show_handles_;
  if (pressed(GLFW_KEY_G)) show_status_ = !show_status_;
  if (pressed(GLFW_KEY_H) || pressed(GLFW_KEY_F1) || (pressed(GLFW_KEY_SLASH) && io.KeyShift)) show_help_ = !show_help_;
  if (pressed(GLFW_KEY_ESCAPE)) show_help_ = false;
  if (pressed(GLFW_KEY_F)) {
    zoom_ = 1;
    pan_ = 0;
  }
  if (pressed(GLFW_KEY_K)) add_keyframe();
  if (pressed(GLFW_KEY_DELETE) || pressed(GLFW_KEY_X)) remove_keyframe();
}

void App::handle_input() {
  ImGuiIO& io = ImGui::GetIO();
  handle_keys();
  const ImVec2 m = io.MousePos;
  const bool in_vp = !io.WantCaptureMouse && m.x >= vp_pos_.x && m.y >= vp_pos_.y && m.x < vp_pos_.x + vp_size_.x &&
                     m.y < vp_pos_.y + vp_size_.y;
  // Zoom about the mouse, pan with the middle button.
  if (in_vp && io.MouseWheel != 0 && renderer_) {
    const cd before = to_world(m);
    zoom_ = std::clamp(zoom_ * std::pow(1.15, io.MouseWheel), 0.1, 50.0);
    view_.pixels_per_unit = compute::View::fit(box_, renderer_->width(), renderer_->height(), 16.0 * scale_ * fb_scale_.x).pixels_per_unit * zoom_;
    const cd after = to_world(m);
    pan_ += before - after;
    view_.world_center += before - after;
  }
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Middle)) middle_drag_ = true;
  if (!ImGui::IsMouseDown(ImGuiMouseButton_Middle)) middle_drag_ = false;
  if (middle_drag_ && (io.MouseDelta.x != 0 || io.MouseDelta.y != 0)) {
    const cd d(io.MouseDelta.x * fb_scale_.x / view_.pixels_per_unit, -io.MouseDelta.y * fb_scale_.y / view_.pixels_per_unit);
    pan_ -= d;
    view_.world_center -= d;
  }

  // Handles under the mouse (on screen at f(handle) of the map shown).
  bool cert = true, is_key = false;
  std::string reason;
  const HarmonicMap* map = shown_map(&cert, &reason, &is_key);
  hover_handle_ = -1;
  if (in_vp && show_handles_ && !scene_.handles.empty() && !drag_.active) {
    const std::vector<cd> img = map_points(setup_->cage, *map, scene_.handles);
    float best = 9.0f * scale_;
    for (size_t k = 0; k < img.size(); ++k) {
      const ImVec2 s = to_screen(img[k]);
      const float d = std::hypot(s.x - m.x, s.y - m.y);
      if (d < best) {
        best = d;
        hover_handle_ = static_cast<int>(k);
      }
    }
  }
  const int key = keyframe_at_frame(cur_);
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !drag_.active) {
    if (hover_handle_ >= 0) {
      if (key >= 0 && !playing_) begin_drag(hover_handle_, key);
      else message("handles are posed at keyframes: pause and step to a keyframe (Page Up / Page Down), or add one here (K)");
    }
  }
  if (in_vp && ImGui::IsMouseReleased(ImGuiMouseButton_Left) && !drag_.active && hover_handle_ < 0 &&
      ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0).x == 0 && ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0).y == 0 &&
      show_handles_)
    add_handle_at(to_world(m));
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Right) && hover_handle_ >= 0 && !drag_.active) remove_handle(hover_handle_);
  if (drag_.active && !drag_.releasing) {
    drag_to(to_world(m));
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) end_drag();
  }
}

// --- drawing -----------------------------------------------------------------------------

void App::draw_viewport_overlays() {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  const ImVec2 a = vp_pos_, b(vp_pos_.x + vp_size_.x, vp_pos_.y + vp_size_.y);
  dl->AddImage(presenter_->frame_texture(), a, b);
  dl->PushClipRect(a, b, true);
  bool cert = true, is_key = false;
  std::string reason;
  const HarmonicMap* map = shown_map(&cert, &reason, &is_key);

  if (show_cage_) {  // the cage (rest plane: the basis lives on it) and its hole points
    const ImU32 col = rgba(0.35f, 0.40f, 0.55f, 0.9f);
    for (const auto& loop : setup_->cage.loops) {
      for (size_t i = 0; i < loop.size(); ++i) {
        dl->AddLine(to_screen(loop[i]), to_screen(loop[(i + 1) % loop.size()]), col, 1.2f * scale_);
        dl->AddCircleFilled(to_screen(loop[i]), 2.2f * scale_, col);
      }
    }
    for (const cd& p : setup_->cage.hole_points) {
      const ImVec2 s = to_screen(p);
      const float r = 4 * scale_;
      dl->AddLine(ImVec2(s.x - r, s.y - r), ImVec2(s.x + r, s.y + r), col, 1.5f * scale_);
      dl->AddLine(ImVec2(s.x - r, s.y + r), ImVec2(s.x + r, s.y - r), col, 1.5f * scale_);
    }
  }
  if (show_handles_ && !scene_.handles.empty()) {
    const std::vector<cd> img = map_points(setup_->cage, *map, scene_.handles);
    const int key = keyframe_at_frame(cur_);
    for (size_t k = 0; k < img.size(); ++k) {
      const ImVec2 s = to_screen(img[k]);
      const bool hot = static_cast<int>(k) == hover_handle_ || (drag_.active && static_cast<int>(k) == drag_.handle);
      const float r = (hot ? 8.0f : 6.0f) * scale_;
      dl->AddCircleFilled(s, r, hot ? rgba(1, 0.85f, 0.2f) : (key >= 0 ? rgba(1, 0.55f, 0.1f) : rgba(0.95f, 0.6f, 0.3f, 0.85f)));
      dl->AddCircle(s, r, rgba(0.08f, 0.08f, 0.1f), 0, 1.5f * scale_);
    }
    if (drag_.active) {  // the target the dragged handle is pulled to
      const ImVec2 t = to_screen(drag_.targets[static_cast<size_t>(drag_.handle)]);
      const float r = 7 * scale_;
      dl->AddLine(ImVec2(t.x - r, t.y), ImVec2(t.x + r, t.y), rgba(0.1f, 0.3f, 0.9f), 2 * scale_);
      dl->AddLine(ImVec2(t.x, t.y - r), ImVec2(t.x, t.y + r), rgba(0.1f, 0.3f, 0.9f), 2 * scale_);
      dl->AddLine(to_screen(img[static_cast<size_t>(drag_.handle)]), t, rgba(0.1f, 0.3f, 0.9f, 0.6f), 1.2f * scale_);
    }
  }

  // Certificate status: a badge (G toggles it); an uncertified frame always gets the
  // banner (and the renderer's red tint and border).
  const float pad = 10 * scale_;
  if (!cert) {
    const std::string text = "NOT CERTIFIED — this frame may fold: " + (reason.empty() ? std::string("no certificate") : reason);
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str(), nullptr, false, vp_size_.x - 4 * pad);
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.80f, 0.05f, 0.05f, 0.95f), 4 * scale_);
    dl->AddText(ImGui::GetFont(), ImGui::GetFontSize(), ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str(), nullptr,
                vp_size_.x - 4 * pad);
  } else if (map && overlap_of(*map).overlaps()) {  // always shown, like the uncertified banner: amber
    const std::string text = std::string(is_key ? "keyframe · " : "") + "certified locally injective, but overlaps itself";
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.90f, 0.52f, 0.02f, 0.95f), 4 * scale_);
    dl->AddText(ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str());
  } else if (show_status_) {
    const std::string text = std::string(is_key ? "keyframe · " : "") + "certified locally injective";
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.10f, 0.50f, 0.22f, 0.92f), 4 * scale_);
    dl->AddText(ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str());
  }

  if (overlays_ & compute::kOverlayDistortion) {  // legend, bottom left
    const float w = std::min(260.0f * scale_, vp_size_.x - 2 * pad), h = 12 * scale_;
    const float fs = ImGui::GetFontSize();
    const ImVec2 p(a.x + pad, b.y - pad - h - fs * 2.4f);
    dl->AddRectFilled(ImVec2(p.x - pad / 2, p.y - pad / 2), ImVec2(p.x + w + pad / 2, b.y - pad / 2), rgba(1, 1, 1, 0.85f),
                      4 * scale_);
    dl->AddText(p, rgba(0.1f, 0.1f, 0.1f), "conformal distortion σ₁/σ₂");
    const float y0 = p.y + fs * 1.2f;
    const int n = 32;
    for (int i = 0; i < n; ++i) {
      const auto c0 = compute::colormap(i / double(n)), c1 = compute::colormap((i + 1) / double(n));
      const ImU32 u0 = rgba(float(c0[0]), float(c0[1]), float(c0[2])), u1 = rgba(float(c1[0]), float(c1[1]), float(c1[2]));
      dl->AddRectFilledMultiColor(ImVec2(p.x + w * float(i) / float(n), y0), ImVec2(p.x + w * float(i + 1) / float(n), y0 + h), u0, u1, u1, u0);
    }
    char lo[32], hi[32];
    std::snprintf(lo, sizeof lo, "1");
    std::snprintf(hi, sizeof hi, "%.2f", dist_hi_);
    dl->AddText(ImVec2(p.x, y0 + h + 1), rgba(0.1f, 0.1f, 0.1f), lo);
    dl->AddText(ImVec2(p.x + w - ImGui::CalcTextSize(hi).x, y0 + h + 1), rgba(0.1f, 0.1f, 0.1f), hi);
  }
  if (drag_.active) {
    const char* t = drag_.releasing ? "solving the keyframe…" : "posing: the point-to-point solve follows the mouse";
    dl->AddText(ImVec2(a.x + pad, b.y - pad - ImGui::GetFontSize()), rgba(0.1f, 0.2f, 0.6f), t);
  }
  dl->PopClipRect();
}

void App::draw_side_panel() {
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(vp_size_.x, 0));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x - vp_size_.x, vp_size_.y));
  ImGui::Begin("##side", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus);
  ImGui::TextUnformatted((scene_.name.empty() ? std::string("scene") : scene_.name).c_str());
  ImGui::SameLine();
  ImGui::TextDisabled("%s%s", std::filesystem::path(o_.scene).filename().string().c_str(), dirty_ ? " (modified)" : "");
  ImGui::TextDisabled("%zu loops · %zu handles · %zu keyframes", static_cast<size_t>(scene_.shape.loop_count()),
                      scene_.handles.size(), scene_.keyframes.size());
  const std::string device = ctx_.info().name.substr(0, ctx_.info().name.find(" ("));
  ImGui::TextDisabled("Newton: %s · Vulkan: %s", solver_->backend().c_str(), device.c_str());
  ImGui::Separator();

  // Performance and the frame's numbers.
  double fps_play = 0;
  const auto now = Clock::now();
  while (!advance_times_.empty() && now - advance_times_.front() > std::chrono::seconds(1)) advance_times_.erase(advance_times_.begin());
  if (playing_) fps_play = static_cast<double>(advance_times_.size());
  if (playing_) ImGui::Text("%.0f fps drawn · %.0f frames/s played", io.Framerate, fps_play);
  else ImGui::Text("%.0f fps drawn · paused", io.Framerate);
  const auto states = solver_->solved_states();
  const auto solved = std::count_if(states.begin(), states.end(), [](uint8_t s) { return s != 0; });
  const auto bad = std::count(states.begin(), states.end(), uint8_t(2));
  const auto unconverged = std::count(states.begin(), states.end(), uint8_t(3));
  bool cert = true, is_key = false;
  std::string reason;
  const HarmonicMap* panel_map = shown_map(&cert, &reason, &is_key);
  if (shown_ && !is_key && shown_index_ == cur_)
    ImGui::Text("solve %.1f ms · %d Newton iterations", shown_->ms, shown_->iterations);
  else if (is_key)
    ImGui::TextUnformatted("keyframe (certified)");
  else
    ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.3f, 1), "solving frame %d…", cur_);
  ImGui::Text("render %.1f ms · solved %lld / %zu frames", render_ms_, static_cast<long long>(solved), states.size());
  if (bad > 0) ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "%lld frame(s) NOT CERTIFIED", static_cast<long long>(bad));
  if (unconverged > 0)
    ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "%lld frame(s) NOT CONVERGED", static_cast<long long>(unconverged));
  if (shown_ && !is_key && shown_index_ == cur_) {
    ImGui::Text("energy %.5f", shown_->energy);
    ImGui::Text("σ₁/σ₂ max %.3f sampled (at breakpoints)", shown_->distortion.conformal_max);
    if (shown_->certified && std::isfinite(shown_->distortion_certified.conformal_max))
      ImGui::Text("σ₁/σ₂ ≤ %.3f certified bound", shown_->distortion_certified.conformal_max);
    if (cert) ImGui::TextColored(ImVec4(0.4f, 0.85f, 0.45f, 1), "certified locally injective");
    else ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "NOT CERTIFIED");
    if (!shown_->converged)
      ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "NOT CONVERGED (Newton stopped after %d iterations)", shown_->iterations);
  }
  if (panel_map && overlap_of(*panel_map).overlaps())  // a drag, a keyframe or a frame: locally, not globally injective
    ImGui::TextColored(ImVec4(1, 0.62f, 0.1f, 1), "overlaps itself (%d boundary crossings)", overlap_.crossings);
  ImGui::Separator();

  ImGui::TextUnformatted("Overlays");
  bool d = overlays_ & compute::kOverlayDistortion, bnd = overlays_ & compute::kOverlayBoundary;
  if (ImGui::Checkbox("distortion (D)", &d)) overlays_ ^= compute::kOverlayDistortion;
  ImGui::SameLine();
  if (ImGui::Checkbox("boundary (B)", &bnd)) overlays_ ^= compute::kOverlayBoundary;
  ImGui::Checkbox("cage (C)", &show_cage_);
  ImGui::SameLine();
  ImGui::Checkbox("handles (P)", &show_handles_);
  ImGui::Checkbox("certificate (G)", &show_status_);
  ImGui::SameLine();
  ImGui::Checkbox("help (H)", &show_help_);
  ImGui::Separator();

  ImGui::TextUnformatted("Keyframes");
  const int key = keyframe_at_frame(cur_);
  if (ImGui::BeginTable("keys", 3, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_ScrollY,
                        ImVec2(0, std::min(6.5f, static_cast<float>(scene_.keyframes.size()) + 0.5f) *
                                      ImGui::GetTextLineHeightWithSpacing()))) {
    for (size_t k = 0; k < scene_.keyframes.size(); ++k) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      char label[32];
      std::snprintf(label, sizeof label, "#%zu", k);
      if (ImGui::Selectable(label, key == static_cast<int>(k), ImGuiSelectableFlags_SpanAllColumns)) {
        playing_ = false;
        cur_ = solver_->frame_at(scene_.keyframes[k].time);
      }
      ImGui::TableNextColumn();
      ImGui::Text("t = %.3g", scene_.keyframes[k].time);
      ImGui::TableNextColumn();
      ImGui::TextDisabled("frame %d", solver_->frame_at(scene_.keyframes[k].time));
    }
    ImGui::EndTable();
  }
  if (ImGui::Button("Add keyframe (K)")) add_keyframe();
  ImGui::SameLine();
  ImGui::BeginDisabled(key < 0 || scene_.keyframes.size() <= 1);
  if (ImGui::Button("Remove (Del)")) remove_keyframe();
  ImGui::EndDisabled();
  ImGui::BeginDisabled(undo_.empty() || drag_.active);
  if (ImGui::Button("Undo")) {
    redo_.push_back(snapshot());
    restore(undo_.back());
    undo_.pop_back();
  }
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(redo_.empty() || drag_.active);
  if (ImGui::Button("Redo")) {
    undo_.push_back(snapshot());
    restore(redo_.back());
    redo_.pop_back();
  }
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Save (Ctrl+S)")) save(o_.output.empty() ? o_.scene : o_.output);
  ImGui::TextWrapped("%s", key >= 0 ? "At a keyframe: drag a handle to pose it; click the shape to add a handle, "
                                      "right-click a handle to remove it."
                                    : "Step to a keyframe (Page Up/Down) to pose it, or press K to make this frame one.");
  if (drag_.active && !drag_.status.empty()) ImGui::TextWrapped("%s", drag_.status.c_str());
  if (!message_.empty() && now - message_time_ < std::chrono::seconds(8)) {
    ImGui::Separator();
    if (message_error_) ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.45f, 0.4f, 1));
    ImGui::TextWrapped("%s", message_.c_str());
    if (message_error_) ImGui::PopStyleColor();
  }
  ImGui::End();
}

void App::draw_timeline() {
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, vp_size_.y));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, io.DisplaySize.y - vp_size_.y));
  ImGui::Begin("##timeline", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoBringToFrontOnFocus);
  const int n = solver_->frame_count();
  const float bw = ImGui::GetFrameHeight() * 1.6f;
  if (ImGui::Button("|<", ImVec2(bw, 0))) {
    playing_ = false;
    cur_ = 0;
  }
  ImGui::SameLine();
  if (ImGui::Button("<", ImVec2(bw, 0))) step(-1);
  ImGui::SameLine();
  if (ImGui::Button(playing_ ? "Pause" : "Play", ImVec2(bw * 2, 0))) toggle_play();
  ImGui::SameLine();
  if (ImGui::Button(">", ImVec2(bw, 0))) step(+1);
  ImGui::SameLine();
  if (ImGui::Button(">|", ImVec2(bw, 0))) {
    playing_ = false;
    cur_ = n - 1;
  }
  ImGui::SameLine();
  ImGui::Checkbox("Loop", &loop_);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(150 * scale_);
  float sp = static_cast<float>(speed_);
  if (ImGui::SliderFloat("speed", &sp, 0.125f, 4.0f, "%.2fx", ImGuiSliderFlags_Logarithmic)) speed_ = sp;
  ImGui::SameLine();
  ImGui::Text("frame %d / %d   t = %.3f", cur_, n - 1, solver_->time_of(cur_));

  // The scrubber, with the keyframes marked and the solved frames as a strip under it.
  ImGui::SetNextItemWidth(-1);
  int f = cur_;
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  if (ImGui::SliderInt("##frame", &f, 0, std::max(0, n - 1), "")) {
    playing_ = false;
    cur_ = f;
  }
  const ImVec2 p1 = ImGui::GetItemRectMax();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float grab = ImGui::GetStyle().GrabMinSize, x0 = p0.x + grab / 2, x1 = p1.x - grab / 2;
  auto x_of = [&](double frame) { return n > 1 ? static_cast<float>(x0 + (x1 - x0) * frame / (n - 1)) : x0; };
  const auto states = solver_->solved_states();
  for (int i = 0; i < n && i < static_cast<int>(states.size()); ++i) {
    if (!states[static_cast<size_t>(i)]) continue;
    const uint8_t st = states[static_cast<size_t>(i)];
    // green: certified and converged; red: not certified; orange: certified, not converged
    const ImU32 c = st == 1 ? rgba(0.3f, 0.75f, 0.4f, 0.9f) : st == 3 ? rgba(1.0f, 0.55f, 0.05f, 1) : rgba(0.95f, 0.15f, 0.15f, 1);
    dl->AddRectFilled(ImVec2(x_of(i - 0.5), p1.y - 3 * scale_), ImVec2(x_of(i + 0.5), p1.y), c);
  }
  for (const Keyframe& k : scene_.keyframes) {
    const float x = x_of(solver_->frame_at(k.time));
    const float s = 5 * scale_;
    dl->AddTriangleFilled(ImVec2(x - s, p0.y), ImVec2(x + s, p0.y), ImVec2(x, p0.y + s * 1.4f), rgba(1, 0.6f, 0.1f));
  }
  ImGui::End();
}

void App::draw_help() {
  if (!show_help_) return;
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(vp_size_.x / 2, vp_size_.y / 2), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowBgAlpha(0.94f);
  ImGui::Begin("Keys (H to close)", &show_help_,
               ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings);
  static const char* keys[][2] = {
      {"Space", "play / pause"},
      {"Left / Right  , .", "step one frame"},
      {"Home / End", "first / last frame"},
      {"Page Up / Down", "previous / next keyframe"},
      {"L", "loop on / off"},
      {"[  ]", "playback speed ÷2 / ×2"},
      {"D", "distortion colour map σ₁/σ₂"},
      {"B", "shape boundary"},
      {"C", "cage (and hole points)"},
      {"P", "handles"},
      {"G", "certificate status badge"},
      {"H  F1  ?", "this help"},
      {"F", "fit the view; wheel zooms, middle-drag pans"},
      {"drag a handle", "pose the keyframe (at a keyframe)"},
      {"click the shape", "add a handle"},
      {"right-click a handle", "remove it"},
      {"K", "add a keyframe here (at the last one: append)"},
      {"Delete  X", "remove the keyframe here"},
      {"Ctrl+Z / Ctrl+Y", "undo / redo"},
      {"Ctrl+S", "save the scene"},
      {"Ctrl+Q", "quit"},
  };
  if (ImGui::BeginTable("help", 2, ImGuiTableFlags_RowBg)) {
    for (const auto& k : keys) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(ImVec4(1, 0.75f, 0.35f, 1), "%s", k[0]);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(k[1]);
    }
    ImGui::EndTable();
  }
  (void)io;
  ImGui::End();
}

// --- scripts ----------------------------------------------------------------------------

void App::run_script() {
  while (script_pc_ < script_.size() && !quit_) {
    const ScriptStep& s = script_[script_pc_];
    auto fail = [&](const std::string& why) {
      std::fprintf(stderr, "hsi-viewer: script step %zu (%s%s): %s\n", script_pc_ + 1, s.op.c_str(),
                   s.line ? (", line " + std::to_string(s.line)).c_str() : "", why.c_str());
      script_failed_ = true;
      quit_ = true;
    };
    if (s.op == "play") {
      if (!playing_) toggle_play();
    } else if (s.op == "pause") {
      playing_ = false;
    } else if (s.op == "frames") {
      if (script_wait_ == 0) {
        script_wait_ = std::max(1, static_cast<int>(number(s, 0)));
        script_wait_start_ = played_frames_;
        return;
      }
      if (played_frames_ - script_wait_start_ < script_wait_ && playing_) return;
      script_wait_ = 0;
    } else if (s.op == "seek") {
      playing_ = false;
      cur_ = std::clamp(static_cast<int>(number(s, 0)), 0, solver_->frame_count() - 1);
    } else if (s.op == "key") {
      static const std::vector<std::pair<std::string, int>> names = {
          {"d", GLFW_KEY_D}, {"b", GLFW_KEY_B}, {"c", GLFW_KEY_C}, {"p", GLFW_KEY_P}, {"g", GLFW_KEY_G}, {"h", GLFW_KEY_H},
          {"l", GLFW_KEY_L}, {"k", GLFW_KEY_K}, {"x", GLFW_KEY_X}, {"space", GLFW_KEY_SPACE}, {"right", GLFW_KEY_RIGHT},
          {"left", GLFW_KEY_LEFT}, {"home", GLFW_KEY_HOME}, {"end", GLFW_KEY_END}, {"f", GLFW_KEY_F}};
      const auto it = std::find_if(names.begin(), names.end(), [&](const auto& k) { return k.first == s.args[0]; });
      if (it == names.end()) return fail("unknown key '" + s.args[0] + "'");
      // As if pressed: through the same handler as the keyboard.
      ImGuiIO& io = ImGui::GetIO();
      io.KeysDown[it->second] = true;
      io.KeysDownDuration[it->second] = 0;
      handle_keys();
      io.KeysDown[it->second] = false;
      io.KeysDownDuration[it->second] = -1;  // not pressed again by this frame's keyboard handling
    } else if (s.op == "add-handle") {
      add_handle_at({number(s, 0), number(s, 1)});
    } else if (s.op == "remove-handle") {
      remove_handle(static_cast<int>(number(s, 0)));
    } else if (s.op == "drag") {
      const int h = static_cast<int>(number(s, 0));
      if (script_wait_ == 0) {
        const int key = keyframe_at_frame(cur_);
        if (key < 0) return fail("frame " + std::to_string(cur_) + " is not a keyframe");
        if (h < 0 || h >= static_cast<int>(scene_.handles.size())) return fail("no handle " + std::to_string(h));
        begin_drag(h, key);
        drag_to({number(s, 1), number(s, 2)});
        end_drag();
        script_wait_ = 1;
        return;
      }
      if (drag_.active) return;  // until the final pose is committed (poll_pose_results ends the drag)
      script_wait_ = 0;
    } else if (s.op == "undo" || s.op == "redo") {
      auto& from = s.op == "undo" ? undo_ : redo_;
      auto& to = s.op == "undo" ? redo_ : undo_;
      if (from.empty()) return fail("nothing to " + s.op);
      to.push_back(snapshot());
      restore(from.back());
      from.pop_back();
    } else if (s.op == "save") {
      if (!save(s.args[0])) return fail("save failed");
    } else if (s.op == "expect-certified") {
      bool cert = true, is_key = false;
      std::string reason;
      shown_map(&cert, &reason, &is_key);
      if (!cert) return fail("frame " + std::to_string(cur_) + " is not certified: " + reason);
    } else if (s.op == "screenshot") {
      // Once the frame shown is the current one, solved and drawn.
      bool cert = true, is_key = false;
      std::string reason;
      shown_map(&cert, &reason, &is_key);
      if (shown_index_ != cur_ || !frame_ready_) return;
      // Two more frames first: ImGui windows that just opened are sized on their first frame.
      if (script_wait_ == 0 && !capture_next_) {
        script_wait_ = 3;
        return;
      }
      if (script_wait_ > 1) {
        --script_wait_;
        return;
      }
      if (!capture_next_) {
        script_wait_ = 0;
        capture_next_ = true;
        capture_path_ = s.args[0];
      }
      return;  // frame() clears capture_next_ once written, then the script moves on
    } else if (s.op == "exit") {
      quit_ = true;
    }
    ++script_pc_;
  }
}

bool App::frame() {
  const auto now = Clock::now();
  const double dt = std::chrono::duration<double>(now - last_time_).count();
  last_time_ = now;

  poll_pose_results();
  if (dirty_ != title_dirty_) {
    title_dirty_ = dirty_;
    const std::string title = "hsi viewer — " + (scene_.name.empty() ? o_.scene : scene_.name) + (dirty_ ? " *" : "");
    glfwSetWindowTitle(window_, title.c_str());
  }
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  layout();

  // Playback: real time (frames wait for the solver), or one solved frame per drawn frame.
  const int n = solver_->frame_count();
  auto advance = [&]() {
    int next = cur_ + 1;
    if (next >= n) {
      if (!loop_) {
        playing_ = false;
        return false;
      }
      next = 0;
    }
    if (keyframe_at_frame(next) < 0 && !solver_->get(next)) return false;
    cur_ = next;
    ++played_frames_;
    advance_times_.push_back(Clock::now());
    return true;
  };
  if (playing_ && n > 1) {
    if (o_.lockstep) {
      if (frame_ready_ && shown_index_ == cur_) advance();
    } else {
      acc_ += std::min(dt, 0.25) * speed_ * o_.rate;
      while (acc_ >= 1 && playing_) {
        if (!advance()) {
          acc_ = std::min(acc_, 1.0);
          break;
        }
        acc_ -= 1;
      }
    }
  }
  solver_->request(cur_, 1);

  if (!script_.empty()) run_script();
  handle_input();
  update_renderer_and_render();
  draw_viewport_overlays();
  draw_side_panel();
  draw_timeline();
  draw_help();
  ImGui::Render();

  RgbaImage shot;
  const bool capturing = capture_next_;
  const bool presented = presenter_->present(ImGui::GetDrawData(), capturing ? &shot : nullptr);
  if (presented) {
    bool cert = true, is_key = false;
    std::string reason;
    shown_map(&cert, &reason, &is_key);
    frame_ready_ = shown_index_ == cur_;
  }
  if (capturing && presented) {
    write_png(capture_path_, shot);
    // Where the viewport is in the image, and what it shows (for tests).
    std::ofstream meta(capture_path_ + ".json");
    bool cert = true, is_key = false;
    std::string reason;
    shown_map(&cert, &reason, &is_key);
    meta << "{\"width\": " << shot.width << ", \"height\": " << shot.height << ", \"viewport\": ["
         << std::lround(vp_pos_.x * fb_scale_.x) << ", " << std::lround(vp_pos_.y * fb_scale_.y) << ", "
         << renderer_->width() << ", " << renderer_->height() << "], \"frame\": " << cur_
         << ", \"time\": " << solver_->time_of(cur_) << ", \"keyframe\": " << (is_key ? "true" : "false")
         << ", \"certified\": " << (cert ? "true" : "false") << "}\n";
    message("screenshot " + capture_path_ + " (frame " + std::to_string(cur_) + ")");
    capture_next_ = false;
    ++script_pc_;
  }
  return !quit_ && !glfwWindowShouldClose(window_);
}

}  // namespace

int run(const Options& o) {
  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "hsi-viewer: GLFW error %d: %s\n", code, text); });
  if (!glfwInit()) throw std::runtime_error("hsi-viewer: cannot initialise GLFW (no display? run under X11/Wayland or xvfb-run)");
  struct GlfwGuard {
    ~GlfwGuard() { glfwTerminate(); }
  } glfw_guard;
  if (!glfwVulkanSupported()) throw compute::VulkanUnavailable("hsi-viewer: GLFW finds no Vulkan loader/driver for windows");
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(o.width, o.height, "hsi viewer", nullptr, nullptr);
  if (!window) throw std::runtime_error("hsi-viewer: cannot open a window");
  struct WindowGuard {
    GLFWwindow* w;
    ~WindowGuard() { glfwDestroyWindow(w); }
  } window_guard{window};

  compute::ContextOptions co;
  co.validation = o.validation;
  co.device_name = o.device;
  co.application_name = "hsi-viewer";
  uint32_t n = 0;
  const char** ext = glfwGetRequiredInstanceExtensions(&n);
  for (uint32_t i = 0; i < n; ++i) co.instance_extensions.emplace_back(ext[i]);
  co.make_surface = [window](VkInstance instance) {
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    const VkResult r = glfwCreateWindowSurface(instance, window, nullptr, &surface);
    if (r != VK_SUCCESS) throw compute::VulkanError(std::string("glfwCreateWindowSurface failed with ") + compute::result_name(r), r);
    return surface;
  };
  std::shared_ptr<compute::ValidationLog> log;
  int status = 0;
  {
    compute::Context ctx(co);
    log = ctx.validation_log();
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForVulkan(window, true);
    struct ImGuiGuard {
      ~ImGuiGuard() {
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
      }
    } imgui_guard;
    {
      App app(o, window, ctx);
      std::printf("hsi-viewer: %s on %s (%s); press H for the keys\n", o.scene.c_str(), ctx.info().name.c_str(),
                  ctx.info().type_name().c_str());
      std::fflush(stdout);
      while (true) {
        glfwPollEvents();
        int w = 0, h = 0;
        glfwGetFramebufferSize(window, &w, &h);
        if (w == 0 || h == 0) {  // minimised
          glfwWaitEvents();
          continue;
        }
        if (!app.frame()) break;
      }
      status = app.script_status();
    }
  }
  if (log && log->count() > 0) {
    std::fprintf(stderr, "hsi-viewer: %s\n", log->summary(20).c_str());
    return 3;
  }
  return status;
}

}  // namespace hsi::viewer
