// The viewer application: the wiring of view, playback, editing, panels and script (app.h).
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
#include <memory>

#include "hsi/basis.h"
#include "hsi/compute/renderer.h"
#include "hsi/inverse_map.h"
#include "hsi/keyframes.h"
#include "hsi/scene_edit.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/scene_texture.h"
#include "hsi/triangulate.h"
#include "panels.h"
#include "playback.h"
#include "presenter.h"
#include "script.h"
#include "solver.h"
#include "view.h"

namespace hsi::viewer {

namespace {

using Clock = std::chrono::steady_clock;

float content_scale(GLFWwindow* window) {
  float xs = 1, ys = 1;
  glfwGetWindowContentScale(window, &xs, &ys);
  return std::max(1.0f, std::max(xs, ys));
}

}  // namespace

App::App(const Options& o, GLFWwindow* window, compute::Context& ctx)
    : o_(o), window_(window), ctx_(ctx), overlays_(parse_overlays(o.overlays)), view_(content_scale(window)),
      script_(script_from_options(o)) {
  if (!script_.empty()) o_.lockstep = true;

  load();
  presenter_ = std::make_unique<Presenter>(ctx_, window_, o.vsync);

  // Fonts: DejaVu Sans (Latin, Greek for σ, arrows) at the content scale.
  const float scale = view_.scale();
  ImGuiIO& io = ImGui::GetIO();
  static const ImWchar ranges[] = {0x0020, 0x00FF, 0x0370, 0x03FF, 0x2000, 0x206F, 0x2070, 0x209F,
                                   0x2190, 0x21FF, 0x2200, 0x22FF, 0x25A0, 0x25FF, 0x2700, 0x27BF, 0};
  const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  if (std::filesystem::exists(font)) {
    io.Fonts->AddFontFromFileTTF(font, std::round(15.0f * scale), nullptr, ranges);
  } else {
    ImFontConfig cfg;
    cfg.SizePixels = std::round(13.0f * scale);
    io.Fonts->AddFontDefault(&cfg);
  }
  ImGui::GetStyle().ScaleAllSizes(scale);
  presenter_->upload_fonts();
  if (o.play && script_.empty()) playback_->toggle_play();  // a script says when to play
}

App::~App() {
  if (presenter_) presenter_->wait_idle();
  solver_.reset();
  renderer_.reset();
  presenter_.reset();
}

void App::load() {
  Scene scene = load_scene(o_.scene);
  if (scene.keyframes.empty()) {  // a bare shape: one keyframe, the identity
    Keyframe k;
    k.time = 0;
    scene.keyframes.push_back(k);
  }
  // Coefficients are stored over a cage: keep the one they were made with.
  if (!scene.cage) scene.cage = build_cage(scene.shape, scene.cage_options);
  setup_ = scene_setup(scene, o_.samples);
  for (Keyframe& k : scene.keyframes)
    if (!k.coefficients && k.targets.empty()) k.coefficients = identity_map(setup_->cage);
  std::printf("hsi-viewer: %s: certifying / solving %zu keyframe(s)\n", o_.scene.c_str(), scene.keyframes.size());
  std::fflush(stdout);
  solve_scene_keyframes(scene, *setup_);

  try {
    solver_ = std::make_unique<Solver>(setup_, o_.rate, runtime::parse_backend(o_.backend));
  } catch (const runtime::BackendUnavailable& e) {
    throw InputError(e.what());  // an option this machine cannot honour: exit status 2, as any bad option
  }
  std::printf("hsi-viewer: Newton core: %s\n", runtime::describe(solver_->backend_choice()).c_str());

  // Texture (or a checkerboard), render mesh, picking and probe points.
  {
    SceneTexture st = scene_texture(scene, o_.scene, false, false);
    texture_ = std::move(st.image);
    texture_rect_ = st.rect;
    texture_filter_ = st.filter;
    overlays_.nearest = st.filter == TextureFilter::Nearest;
    if (!st.checker)
      std::printf("hsi-viewer: texture %s, %s filtering\n", scene.texture_path().string().c_str(),
                  texture_filter_name(st.filter));
  }
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(scene.shape, o_.mesh_vertices);
  mesh_ = triangulate(scene.shape, to);
  inverse_ = std::make_unique<InverseMap>(scene.shape, setup_->cage);
  std::vector<cd> probe;
  for (int v = 0; v < mesh_.vertex_count(); ++v)
    if (mesh_.boundary_loop[static_cast<size_t>(v)] >= 0) probe.push_back(mesh_.vertices[static_cast<size_t>(v)]);
  probe_rows_ = evaluate_basis(setup_->cage, probe, kBasisC | kBasisD);
  editor_ = std::make_unique<SceneEditor>(std::move(scene));
  playback_ = std::make_unique<Playback>(*solver_, editor_->scene().keyframes, o_.rate, o_.lockstep);
  playback_->loop = o_.loop;
  playback_->speed = o_.speed;
  keyframes_changed();
}

void App::keyframes_changed() {
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : editor_->scene().keyframes) {
    times.push_back(k.time);
    maps.push_back(*k.coefficients);
  }
  solver_->set_keyframes(times, maps, scene_timings(editor_->scene()));
  const Framing framing = frame_keyframes(probe_rows_, maps);
  view_.set_box(framing.box);
  dist_hi_ = framing.dist_hi;
  playback_->clamp_to_timeline();
  shown_.reset();
  shown_index_ = -1;
  rendered_map_ = nullptr;
}

void App::message(const std::string& m, bool error) {
  message_ = {m, error, Clock::now()};
  std::printf("hsi-viewer: %s\n", m.c_str());
  std::fflush(stdout);
}

EditFrame App::edit_frame() const {
  const int cur = playback_->current();
  return {cur, solver_->time_of(cur), playback_->keyframe_at(cur), nullptr, false};
}

void App::add_keyframe() {
  EditFrame at = edit_frame();
  const auto solved = solver_->get(at.index);  // kept alive while the editor reads it
  if (solved) {
    at.solved = &solved->map;
    at.certified = solved->certified;
  }
  const EditOutcome o = editor_->add_keyframe(at);
  if (o.done) {
    keyframes_changed();
    playback_->seek(solver_->frame_at(editor_->scene().keyframes[static_cast<size_t>(o.index)].time));
  }
  show(o);
}

void App::remove_keyframe() {
  const EditOutcome o = editor_->remove_keyframe(edit_frame());
  if (o.done) keyframes_changed();
  show(o);
}

void App::add_handle_at(cd world) {
  const Shown s = shown();
  show(editor_->add_handle(inverse_->rest_point(*s.map, world)));
}

void App::remove_handle(int h) {
  const EditOutcome o = editor_->remove_handle(h);
  if (o.done) hover_handle_ = -1;
  show(o);
}

std::string App::set_timing(int k, KeyTiming timing) {
  const EditOutcome o = editor_->set_timing(k, timing);
  if (o.done) keyframes_changed();
  show(o);
  return o.done ? "" : o.message;
}

std::string App::undo_redo(bool undo) {
  const EditOutcome o = undo ? editor_->undo() : editor_->redo();
  if (o.done) keyframes_changed();
  show(o);
  if (o.done) return "";
  return o.message.empty() ? "a handle is being dragged" : o.message;
}

bool App::begin_drag(int handle, const EditFrame& at) {
  const EditOutcome o = editor_->begin_pose(handle, at);
  show(o);
  if (!o.done) return false;
  drag_ = Drag();
  playback_->pause();
  return true;
}

std::string App::drag(int h, cd target) {
  if (editor_->pose()) return "a handle is being dragged already";
  const EditOutcome o = editor_->begin_pose(h, edit_frame());
  if (!o.done) return o.message;
  drag_ = Drag();
  playback_->pause();
  drag_to(target);
  end_drag();
  return "";
}

void App::request_pose(bool final) {
  const HandlePose* p = editor_->pose();
  PoseRequest r;
  r.id = ++pose_id_;
  r.keyframe = p->keyframe;
  r.handles = editor_->scene().handles;
  r.targets = p->targets;
  r.start = p->latest;
  r.final = final;
  if (final) drag_.final_id = r.id;
  solver_->pose(std::move(r));
}

void App::drag_to(cd world) {
  if (!editor_->pose() || drag_.releasing) return;
  if (editor_->move_pose_target(world)) request_pose(false);
}

void App::end_drag() {
  if (!editor_->pose() || drag_.releasing) return;
  drag_.releasing = true;
  request_pose(true);
}

void App::poll_pose_results() {
  while (auto res = solver_->take_pose_result()) {
    if (!editor_->pose()) continue;
    if (!res->error.empty()) {
      message("pose: " + res->error, true);
      if (res->id == drag_.final_id) {
        editor_->cancel_pose();
        drag_ = Drag();
      }
      continue;
    }
    if (res->id != drag_.final_id) {
      editor_->pose_solved(res->result);
      continue;
    }
    const EditOutcome o = editor_->commit_pose(res->result, res->targets);
    drag_ = Drag();
    keyframes_changed();
    show(o);
  }
}

bool App::save(const std::string& path) {
  try {
    Scene out = editor_->scene();
    const std::filesystem::path p(path);
    if (p.parent_path() != std::filesystem::path(o_.scene).parent_path() && !out.texture.empty() && out.texture.is_relative())
      out.texture = std::filesystem::relative(out.texture_path(), p.parent_path().empty() ? "." : p.parent_path());
    save_scene(out, p);
    if (path == output_path()) editor_->mark_saved();
    keyframes_changed();
    message("saved " + path);
    return true;
  } catch (const std::exception& e) {
    message(std::string("could not save: ") + e.what(), true);
    return false;
  }
}

// --- the frame shown ---------------------------------------------------------------------

// The map on screen: a drag's latest certified pose, the keyframe itself at a
// keyframe's frame, else the solved frame (or the last one shown while it solves).
Shown App::shown() {
  Shown s;
  if (const HandlePose* p = editor_->pose()) {
    s.is_key = true;
    s.map = &p->latest;
    return s;
  }
  const auto& keys = editor_->scene().keyframes;
  const int cur = playback_->current();
  const int key = playback_->keyframe_at(cur);
  if (key >= 0) {
    s.is_key = true;
    shown_index_ = cur;
    s.map = &*keys[static_cast<size_t>(key)].coefficients;
    return s;
  }
  if (auto f = solver_->get(cur)) {
    shown_ = f;
    shown_index_ = cur;
  }
  if (!shown_) {
    s.map = &*keys.front().coefficients;
    return s;
  }
  s.certified = shown_->certified;
  s.reason = shown_->message;
  s.map = &shown_->map;
  return s;
}

bool App::shown_certified(std::string* reason) {
  const Shown s = shown();
  *reason = s.reason;
  return s.certified;
}

bool App::current_frame_drawn() {
  shown();
  return shown_index_ == playback_->current() && frame_ready_;
}

const OverlapResult& App::overlap_of(const HarmonicMap& map) {
  if (overlap_phi_.size() != map.phi.size() || overlap_phi_ != map.phi || overlap_psi_ != map.psi) {
    overlap_ = setup_->overlap.check(map);
    overlap_phi_ = map.phi;
    overlap_psi_ = map.psi;
  }
  return overlap_;
}

void App::render() {
  const int w = view_.pixel_width(), h = view_.pixel_height();
  if (!renderer_ || renderer_->width() != w || renderer_->height() != h) {
    presenter_->wait_idle();
    renderer_.reset();
    renderer_ = std::make_unique<compute::Renderer>(ctx_, w, h);
    renderer_->set_mesh(mesh_, editor_->scene().handles);
    renderer_->set_texture(texture_, texture_rect_, texture_filter_);
    rendered_map_ = nullptr;
  }
  // The texture filter, as toggled (N, or the side panel).
  if (const TextureFilter want = overlays_.nearest ? TextureFilter::Nearest : TextureFilter::Linear; want != texture_filter_) {
    presenter_->wait_idle();
    texture_filter_ = want;
    renderer_->set_texture(texture_, texture_rect_, texture_filter_);
    rendered_map_ = nullptr;
  }
  const compute::View& camera = view_.update_camera(w, h);

  const Shown s = shown();
  const HarmonicMap* map = s.map;
  // A signature of everything the image depends on besides the map's address.
  uint64_t sig = overlays_.render * 1315423911ull ^ static_cast<uint64_t>(s.certified) * 2654435761ull;
  auto mix = [&](double v) {
    uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    sig = (sig ^ b) * 1099511628211ull;
  };
  mix(camera.pixels_per_unit);
  mix(camera.world_center.real());
  mix(camera.world_center.imag());
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
  style.overlays = overlays_.render & (compute::kOverlayDistortion | compute::kOverlayBoundary);
  style.background = {0.97f, 0.97f, 0.98f, 1};
  style.distortion_lo = 1;
  style.distortion_hi = dist_hi_;
  style.boundary_width_px = std::max(1.5f, 1.5f * view_.scale() * view_.fb_scale().x);
  style.uncertified = !s.certified;
  const auto t0 = Clock::now();
  presenter_->set_frame_image(renderer_->render(setup_->cage, *map, camera, style));
  render_ms_ = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  rendered_map_ = map;
  rendered_sig_ = sig;
}

// --- input -----------------------------------------------------------------------------

void App::handle_keys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  auto pressed = [](int key) { return ImGui::IsKeyPressed(key, false); };
  auto repeated = [](int key) { return ImGui::IsKeyPressed(key, true); };
  if (io.KeyCtrl) {
    if (pressed(GLFW_KEY_Z) && !io.KeyShift) undo_redo(true);
    else if (pressed(GLFW_KEY_Y) || (pressed(GLFW_KEY_Z) && io.KeyShift)) undo_redo(false);
    else if (pressed(GLFW_KEY_S)) save(output_path());
    else if (pressed(GLFW_KEY_Q)) quit_ = true;
    return;
  }
  Playback& play = *playback_;
  if (pressed(GLFW_KEY_SPACE)) play.toggle_play();
  if (repeated(GLFW_KEY_RIGHT) || repeated(GLFW_KEY_PERIOD)) play.step(+1);
  if (repeated(GLFW_KEY_LEFT) || repeated(GLFW_KEY_COMMA)) play.step(-1);
  if (pressed(GLFW_KEY_HOME)) play.seek(0);
  if (pressed(GLFW_KEY_END)) play.seek(solver_->frame_count() - 1);
  if (pressed(GLFW_KEY_PAGE_UP) || pressed(GLFW_KEY_PAGE_DOWN)) play.to_keyframe(pressed(GLFW_KEY_PAGE_DOWN));
  if (pressed(GLFW_KEY_L)) play.loop = !play.loop;
  if (pressed(GLFW_KEY_LEFT_BRACKET)) play.speed = std::max(0.125, play.speed / 2);
  if (pressed(GLFW_KEY_RIGHT_BRACKET)) play.speed = std::min(8.0, play.speed * 2);
  if (pressed(GLFW_KEY_D)) overlays_.render ^= compute::kOverlayDistortion;
  if (pressed(GLFW_KEY_B)) overlays_.render ^= compute::kOverlayBoundary;
  if (pressed(GLFW_KEY_C)) overlays_.cage = !overlays_.cage;
  if (pressed(GLFW_KEY_P)) overlays_.handles = !overlays_.handles;
  if (pressed(GLFW_KEY_G)) overlays_.status = !overlays_.status;
  if (pressed(GLFW_KEY_N)) overlays_.nearest = !overlays_.nearest;
  if (pressed(GLFW_KEY_H) || pressed(GLFW_KEY_F1) || (pressed(GLFW_KEY_SLASH) && io.KeyShift)) overlays_.help = !overlays_.help;
  if (pressed(GLFW_KEY_ESCAPE)) overlays_.help = false;
  if (pressed(GLFW_KEY_F)) view_.fit();
  if (pressed(GLFW_KEY_K)) add_keyframe();
  if (pressed(GLFW_KEY_DELETE) || pressed(GLFW_KEY_X)) remove_keyframe();
}

void App::press_key(int key) {
  // As if pressed: through the same handler as the keyboard.
  ImGuiIO& io = ImGui::GetIO();
  io.KeysDown[key] = true;
  io.KeysDownDuration[key] = 0;
  handle_keys();
  io.KeysDown[key] = false;
  io.KeysDownDuration[key] = -1;  // not pressed again by this frame's keyboard handling
}

void App::handle_input() {
  ImGuiIO& io = ImGui::GetIO();
  handle_keys();
  const ImVec2 m = io.MousePos;
  const bool in_vp = !io.WantCaptureMouse && view_.contains(m);
  view_.handle_mouse(in_vp);

  // Handles under the mouse (on screen at f(handle) of the map shown).
  const Scene& scene = editor_->scene();
  hover_handle_ = -1;
  if (in_vp && overlays_.handles && !scene.handles.empty() && !editor_->pose()) {
    const std::vector<cd> img = map_points(setup_->cage, *shown().map, scene.handles);
    float best = 9.0f * view_.scale();
    for (size_t k = 0; k < img.size(); ++k) {
      const ImVec2 s = view_.to_screen(img[k]);
      const float d = std::hypot(s.x - m.x, s.y - m.y);
      if (d < best) {
        best = d;
        hover_handle_ = static_cast<int>(k);
      }
    }
  }
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !editor_->pose() && hover_handle_ >= 0) {
    EditFrame at = edit_frame();
    if (playback_->playing()) at.keyframe = -1;  // while playing no keyframe stays on screen: pose when paused
    begin_drag(hover_handle_, at);
  }
  if (in_vp && ImGui::IsMouseReleased(ImGuiMouseButton_Left) && !editor_->pose() && hover_handle_ < 0 &&
      ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0).x == 0 && ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0).y == 0 &&
      overlays_.handles)
    add_handle_at(view_.to_world(m));
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Right) && hover_handle_ >= 0 && !editor_->pose())
    remove_handle(hover_handle_);
  if (editor_->pose() && !drag_.releasing) {
    drag_to(view_.to_world(m));
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) end_drag();
  }
}

// --- drawing and the frame -----------------------------------------------------------------

void App::draw_panels() {
  const Shown s = shown();
  const int cur = playback_->current();
  const SolvedFrame* frame = shown_ && !s.is_key && shown_index_ == cur ? shown_.get() : nullptr;
  const std::string device = ctx_.info().name.substr(0, ctx_.info().name.find(" ("));
  const PanelContext c{*editor_,     o_.scene,   setup_->cage,         *solver_, device, *playback_,
                       overlays_,    view_,      presenter_->frame_texture(), s,   frame,  &overlap_of(*s.map),
                       render_ms_,   dist_hi_,   hover_handle_,        drag_.releasing,  message_};
  draw_viewport_overlays(c);
  PanelRequests req = draw_side_panel(c);
  const PanelRequests timeline = draw_timeline(c);
  if (timeline.timing_keyframe >= 0) {
    req.timing_keyframe = timeline.timing_keyframe;
    req.timing = timeline.timing;
  }
  draw_help(overlays_, view_);
  // After drawing: an edit may move the keyframes the panels were given.
  if (req.add_keyframe) add_keyframe();
  if (req.remove_keyframe) remove_keyframe();
  if (req.timing_keyframe >= 0) set_timing(req.timing_keyframe, req.timing);
  if (req.undo) undo_redo(true);
  if (req.redo) undo_redo(false);
  if (req.save) save(output_path());
}

void App::write_capture(const RgbaImage& shot) {
  const std::string path = *script_.capture_path();
  write_png(path, shot);
  // Where the viewport is in the image, and what it shows (for tests).
  std::ofstream meta(path + ".json");
  const Shown s = shown();
  const int cur = playback_->current();
  meta << "{\"width\": " << shot.width << ", \"height\": " << shot.height << ", \"viewport\": ["
       << std::lround(view_.pos().x * view_.fb_scale().x) << ", " << std::lround(view_.pos().y * view_.fb_scale().y) << ", "
       << renderer_->width() << ", " << renderer_->height() << "], \"frame\": " << cur
       << ", \"time\": " << solver_->time_of(cur) << ", \"keyframe\": " << (s.is_key ? "true" : "false")
       << ", \"certified\": " << (s.certified ? "true" : "false") << "}\n";
  message("screenshot " + path + " (frame " + std::to_string(cur) + ")");
  script_.captured();
}

bool App::frame() {
  const auto now = Clock::now();
  const double dt = std::chrono::duration<double>(now - last_time_).count();
  last_time_ = now;

  poll_pose_results();
  if (editor_->modified() != title_dirty_) {
    title_dirty_ = editor_->modified();
    const std::string& name = editor_->scene().name;
    const std::string title = "hsi viewer — " + (name.empty() ? o_.scene : name) + (title_dirty_ ? " *" : "");
    glfwSetWindowTitle(window_, title.c_str());
  }
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  view_.layout();

  // Playback: real time (frames wait for the solver), or one solved frame per drawn frame.
  playback_->advance(dt, frame_ready_ && shown_index_ == playback_->current());
  solver_->request(playback_->current(), 1);

  if (!script_.empty()) script_.run(*this);
  handle_input();
  render();
  draw_panels();
  ImGui::Render();

  RgbaImage shot;
  const bool capturing = script_.capture_path() != nullptr;
  const bool presented = presenter_->present(ImGui::GetDrawData(), capturing ? &shot : nullptr);
  if (presented) {
    shown();
    frame_ready_ = shown_index_ == playback_->current();
  }
  if (capturing && presented) write_capture(shot);
  return !quit_ && !script_.quit() && !glfwWindowShouldClose(window_);
}

}  // namespace hsi::viewer
