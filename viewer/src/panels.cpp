// The viewer's ImGui panels: viewport overlays, side panel, timeline, help.
#include "panels.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace hsi::viewer {

namespace {

ImU32 rgba(float r, float g, float b, float a = 1) { return ImGui::ColorConvertFloat4ToU32(ImVec4(r, g, b, a)); }

}  // namespace

Overlays parse_overlays(const std::string& list) {
  Overlays o;
  o.handles = o.status = false;  // on when named
  for (std::stringstream ss(list); ss.good();) {
    std::string s;
    std::getline(ss, s, ',');
    if (s == "distortion") o.render |= compute::kOverlayDistortion;
    else if (s == "boundary") o.render |= compute::kOverlayBoundary;
    else if (s == "cage") o.cage = true;
    else if (s == "handles") o.handles = true;
    else if (s == "status") o.status = true;
    else if (s == "help") o.help = true;
    else if (s != "none" && !s.empty())
      throw InputError("--overlays: unknown overlay '" + s + "' (distortion, boundary, cage, handles, status, help, none)");
  }
  return o;
}

void draw_viewport_overlays(const PanelContext& c) {
  const View& v = c.view;
  const float scale = v.scale();
  const HandlePose* pose = c.editor.pose();
  const Scene& scene = c.editor.scene();
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  const ImVec2 a = v.pos(), b(v.pos().x + v.size().x, v.pos().y + v.size().y);
  dl->AddImage(c.frame_texture, a, b);
  dl->PushClipRect(a, b, true);

  if (c.overlays.cage) {  // the cage (rest plane: the basis lives on it) and its hole points
    const ImU32 col = rgba(0.35f, 0.40f, 0.55f, 0.9f);
    for (const auto& loop : c.cage.loops) {
      for (size_t i = 0; i < loop.size(); ++i) {
        dl->AddLine(v.to_screen(loop[i]), v.to_screen(loop[(i + 1) % loop.size()]), col, 1.2f * scale);
        dl->AddCircleFilled(v.to_screen(loop[i]), 2.2f * scale, col);
      }
    }
    for (const cd& p : c.cage.hole_points) {
      const ImVec2 s = v.to_screen(p);
      const float r = 4 * scale;
      dl->AddLine(ImVec2(s.x - r, s.y - r), ImVec2(s.x + r, s.y + r), col, 1.5f * scale);
      dl->AddLine(ImVec2(s.x - r, s.y + r), ImVec2(s.x + r, s.y - r), col, 1.5f * scale);
    }
  }
  if (c.overlays.handles && !scene.handles.empty()) {
    const std::vector<cd> img = map_points(c.cage, *c.shown.map, scene.handles);
    const int key = c.playback.keyframe_at(c.playback.current());
    for (size_t k = 0; k < img.size(); ++k) {
      const ImVec2 s = v.to_screen(img[k]);
      const bool hot = static_cast<int>(k) == c.hover_handle || (pose && static_cast<int>(k) == pose->handle);
      const float r = (hot ? 8.0f : 6.0f) * scale;
      dl->AddCircleFilled(s, r, hot ? rgba(1, 0.85f, 0.2f) : (key >= 0 ? rgba(1, 0.55f, 0.1f) : rgba(0.95f, 0.6f, 0.3f, 0.85f)));
      dl->AddCircle(s, r, rgba(0.08f, 0.08f, 0.1f), 0, 1.5f * scale);
    }
    if (pose) {  // the target the dragged handle is pulled to
      const ImVec2 t = v.to_screen(pose->targets[static_cast<size_t>(pose->handle)]);
      const float r = 7 * scale;
      dl->AddLine(ImVec2(t.x - r, t.y), ImVec2(t.x + r, t.y), rgba(0.1f, 0.3f, 0.9f), 2 * scale);
      dl->AddLine(ImVec2(t.x, t.y - r), ImVec2(t.x, t.y + r), rgba(0.1f, 0.3f, 0.9f), 2 * scale);
      dl->AddLine(v.to_screen(img[static_cast<size_t>(pose->handle)]), t, rgba(0.1f, 0.3f, 0.9f, 0.6f), 1.2f * scale);
    }
  }

  // Certificate status: a badge (G toggles it); an uncertified frame always gets the
  // banner (and the renderer's red tint and border).
  const float pad = 10 * scale;
  const std::string key_note = c.shown.is_key ? "keyframe · " : "";
  if (!c.shown.certified) {
    const std::string text =
        "NOT CERTIFIED — this frame may fold: " + (c.shown.reason.empty() ? std::string("no certificate") : c.shown.reason);
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str(), nullptr, false, v.size().x - 4 * pad);
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.80f, 0.05f, 0.05f, 0.95f), 4 * scale);
    dl->AddText(ImGui::GetFont(), ImGui::GetFontSize(), ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str(), nullptr,
                v.size().x - 4 * pad);
  } else if (c.overlap && c.overlap->overlaps()) {  // always shown, like the uncertified banner: amber
    const std::string text = key_note + "certified locally injective, but overlaps itself";
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.90f, 0.52f, 0.02f, 0.95f), 4 * scale);
    dl->AddText(ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str());
  } else if (c.overlays.status) {
    const std::string text = key_note + "certified locally injective";
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
    const ImVec2 p(a.x + pad, a.y + pad);
    dl->AddRectFilled(p, ImVec2(p.x + ts.x + 2 * pad, p.y + ts.y + pad), rgba(0.10f, 0.50f, 0.22f, 0.92f), 4 * scale);
    dl->AddText(ImVec2(p.x + pad, p.y + pad / 2), rgba(1, 1, 1), text.c_str());
  }

  if (c.overlays.render & compute::kOverlayDistortion) {  // legend, bottom left
    const float w = std::min(260.0f * scale, v.size().x - 2 * pad), h = 12 * scale;
    const float fs = ImGui::GetFontSize();
    const ImVec2 p(a.x + pad, b.y - pad - h - fs * 2.4f);
    dl->AddRectFilled(ImVec2(p.x - pad / 2, p.y - pad / 2), ImVec2(p.x + w + pad / 2, b.y - pad / 2), rgba(1, 1, 1, 0.85f),
                      4 * scale);
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
    std::snprintf(hi, sizeof hi, "%.2f", c.dist_hi);
    dl->AddText(ImVec2(p.x, y0 + h + 1), rgba(0.1f, 0.1f, 0.1f), lo);
    dl->AddText(ImVec2(p.x + w - ImGui::CalcTextSize(hi).x, y0 + h + 1), rgba(0.1f, 0.1f, 0.1f), hi);
  }
  if (pose) {
    const char* t = c.releasing ? "solving the keyframe…" : "posing: the point-to-point solve follows the mouse";
    dl->AddText(ImVec2(a.x + pad, b.y - pad - ImGui::GetFontSize()), rgba(0.1f, 0.2f, 0.6f), t);
  }
  dl->PopClipRect();
}

PanelRequests draw_side_panel(const PanelContext& c) {
  PanelRequests req;
  const Scene& scene = c.editor.scene();
  Playback& play = c.playback;
  const ImVec2 vp = c.view.size();
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(vp.x, 0));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x - vp.x, vp.y));
  ImGui::Begin("##side", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus);
  ImGui::TextUnformatted((scene.name.empty() ? std::string("scene") : scene.name).c_str());
  ImGui::SameLine();
  ImGui::TextDisabled("%s%s", std::filesystem::path(c.scene_file).filename().string().c_str(),
                      c.editor.modified() ? " (modified)" : "");
  ImGui::TextDisabled("%zu loops · %zu handles · %zu keyframes", static_cast<size_t>(scene.shape.loop_count()),
                      scene.handles.size(), scene.keyframes.size());
  ImGui::TextDisabled("Newton: %s · Vulkan: %s", c.solver.backend().c_str(), c.device.c_str());
  ImGui::Separator();

  // Performance and the frame's numbers.
  const double fps_play = play.frames_per_second();
  if (play.playing()) ImGui::Text("%.0f fps drawn · %.0f frames/s played", io.Framerate, fps_play);
  else ImGui::Text("%.0f fps drawn · paused", io.Framerate);
  const auto states = c.solver.solved_states();
  const auto solved = std::count_if(states.begin(), states.end(), [](uint8_t s) { return s != 0; });
  const auto bad = std::count(states.begin(), states.end(), uint8_t(2));
  const auto unconverged = std::count(states.begin(), states.end(), uint8_t(3));
  const SolvedFrame* f = c.frame;
  if (f)
    ImGui::Text("solve %.1f ms · %d Newton iterations", f->ms, f->iterations);
  else if (c.shown.is_key)
    ImGui::TextUnformatted("keyframe (certified)");
  else
    ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.3f, 1), "solving frame %d…", play.current());
  ImGui::Text("render %.1f ms · solved %lld / %zu frames", c.render_ms, static_cast<long long>(solved), states.size());
  if (bad > 0) ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "%lld frame(s) NOT CERTIFIED", static_cast<long long>(bad));
  if (unconverged > 0)
    ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "%lld frame(s) NOT CONVERGED", static_cast<long long>(unconverged));
  if (f) {
    ImGui::Text("energy %.5f", f->energy);
    ImGui::Text("σ₁/σ₂ max %.3f sampled (at breakpoints)", f->distortion.conformal_max);
    if (f->certified && std::isfinite(f->distortion_certified.conformal_max))
      ImGui::Text("σ₁/σ₂ ≤ %.3f certified bound", f->distortion_certified.conformal_max);
    if (c.shown.certified) ImGui::TextColored(ImVec4(0.4f, 0.85f, 0.45f, 1), "certified locally injective");
    else ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "NOT CERTIFIED");
    if (!f->converged)
      ImGui::TextColored(ImVec4(1, 0.6f, 0.1f, 1), "NOT CONVERGED (%s after %d iterations)", to_string(f->stop), f->iterations);
  }
  if (c.overlap && c.overlap->overlaps())  // a drag, a keyframe or a frame: locally, not globally injective
    ImGui::TextColored(ImVec4(1, 0.62f, 0.1f, 1), "overlaps itself (%d boundary crossings)", c.overlap->crossings);
  ImGui::Separator();

  ImGui::TextUnformatted("Overlays");
  Overlays& ov = c.overlays;
  bool d = ov.render & compute::kOverlayDistortion, bnd = ov.render & compute::kOverlayBoundary;
  if (ImGui::Checkbox("distortion (D)", &d)) ov.render ^= compute::kOverlayDistortion;
  ImGui::SameLine();
  if (ImGui::Checkbox("boundary (B)", &bnd)) ov.render ^= compute::kOverlayBoundary;
  ImGui::Checkbox("cage (C)", &ov.cage);
  ImGui::SameLine();
  ImGui::Checkbox("handles (P)", &ov.handles);
  ImGui::Checkbox("certificate (G)", &ov.status);
  ImGui::SameLine();
  ImGui::Checkbox("help (H)", &ov.help);
  ImGui::Checkbox("nearest texels (N)", &ov.nearest);
  ImGui::Separator();

  ImGui::TextUnformatted("Keyframes");
  const int key = play.keyframe_at(play.current());
  if (ImGui::BeginTable("keys", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_ScrollY,
                        ImVec2(0, std::min(6.5f, static_cast<float>(scene.keyframes.size()) + 0.5f) *
                                      ImGui::GetTextLineHeightWithSpacing()))) {
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      char label[32];
      std::snprintf(label, sizeof label, "#%zu", k);
      const int frame = c.solver.frame_at(scene.keyframes[k].time);
      if (ImGui::Selectable(label, key == static_cast<int>(k), ImGuiSelectableFlags_SpanAllColumns)) play.seek(frame);
      ImGui::TableNextColumn();
      ImGui::Text("t = %.3g", scene.keyframes[k].time);
      ImGui::TableNextColumn();
      ImGui::TextDisabled("frame %d", frame);
      // How the interval leaving this keyframe is travelled (none leaves the last one).
      ImGui::TableNextColumn();
      if (k + 1 < scene.keyframes.size()) {
        static const KeyTiming modes[] = {KeyTiming::Linear, KeyTiming::Smooth, KeyTiming::Ease, KeyTiming::Hold};
        const KeyTiming now = scene.keyframes[k].timing;
        ImGui::PushID(static_cast<int>(k));
        ImGui::SetNextItemWidth(-1);
        if (ImGui::BeginCombo("##timing", to_string(now))) {
          for (KeyTiming m : modes)
            if (ImGui::Selectable(to_string(m), m == now) && m != now) {
              req.timing_keyframe = static_cast<int>(k);
              req.timing = m;
            }
          ImGui::EndCombo();
        }
        ImGui::PopID();
      }
    }
    ImGui::EndTable();
  }
  req.add_keyframe = ImGui::Button("Add keyframe (K)");
  ImGui::SameLine();
  ImGui::BeginDisabled(key < 0 || scene.keyframes.size() <= 1);
  req.remove_keyframe = ImGui::Button("Remove (Del)");
  ImGui::EndDisabled();
  ImGui::BeginDisabled(!c.editor.can_undo());
  req.undo = ImGui::Button("Undo");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!c.editor.can_redo());
  req.redo = ImGui::Button("Redo");
  ImGui::EndDisabled();
  ImGui::SameLine();
  req.save = ImGui::Button("Save (Ctrl+S)");
  ImGui::TextWrapped("%s", key >= 0 ? "At a keyframe: drag a handle to pose it; click the shape to add a handle, "
                                      "right-click a handle to remove it."
                                    : "Step to a keyframe (Page Up/Down) to pose it, or press K to make this frame one.");
  if (const HandlePose* pose = c.editor.pose(); pose && !pose->status.empty()) ImGui::TextWrapped("%s", pose->status.c_str());
  if (!c.message.text.empty() && std::chrono::steady_clock::now() - c.message.time < std::chrono::seconds(8)) {
    ImGui::Separator();
    if (c.message.error) ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.45f, 0.4f, 1));
    ImGui::TextWrapped("%s", c.message.text.c_str());
    if (c.message.error) ImGui::PopStyleColor();
  }
  ImGui::End();
  return req;
}

PanelRequests draw_timeline(const PanelContext& c) {
  PanelRequests req;
  Playback& play = c.playback;
  const float scale = c.view.scale();
  const ImVec2 vp = c.view.size();
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, vp.y));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, io.DisplaySize.y - vp.y));
  ImGui::Begin("##timeline", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoBringToFrontOnFocus);
  const int n = c.solver.frame_count();
  const float bw = ImGui::GetFrameHeight() * 1.6f;
  if (ImGui::Button("|<", ImVec2(bw, 0))) play.seek(0);
  ImGui::SameLine();
  if (ImGui::Button("<", ImVec2(bw, 0))) play.step(-1);
  ImGui::SameLine();
  if (ImGui::Button(play.playing() ? "Pause" : "Play", ImVec2(bw * 2, 0))) play.toggle_play();
  ImGui::SameLine();
  if (ImGui::Button(">", ImVec2(bw, 0))) play.step(+1);
  ImGui::SameLine();
  if (ImGui::Button(">|", ImVec2(bw, 0))) play.seek(n - 1);
  ImGui::SameLine();
  ImGui::Checkbox("Loop", &play.loop);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(150 * scale);
  float sp = static_cast<float>(play.speed);
  if (ImGui::SliderFloat("speed", &sp, 0.125f, 4.0f, "%.2fx", ImGuiSliderFlags_Logarithmic)) play.speed = sp;
  ImGui::SameLine();
  ImGui::Text("frame %d / %d   t = %.3f", play.current(), n - 1, c.solver.time_of(play.current()));

  // The scrubber, with the keyframes marked and the solved frames as a strip under it.
  ImGui::SetNextItemWidth(-1);
  int f = play.current();
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  if (ImGui::SliderInt("##frame", &f, 0, std::max(0, n - 1), "")) play.seek(f);
  const ImVec2 p1 = ImGui::GetItemRectMax();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float grab = ImGui::GetStyle().GrabMinSize, x0 = p0.x + grab / 2, x1 = p1.x - grab / 2;
  auto x_of = [&](double frame) { return n > 1 ? static_cast<float>(x0 + (x1 - x0) * frame / (n - 1)) : x0; };
  const auto states = c.solver.solved_states();
  for (int i = 0; i < n && i < static_cast<int>(states.size()); ++i) {
    if (!states[static_cast<size_t>(i)]) continue;
    const uint8_t st = states[static_cast<size_t>(i)];
    // green: certified and converged; red: not certified; orange: certified, not converged
    const ImU32 col = st == 1 ? rgba(0.3f, 0.75f, 0.4f, 0.9f) : st == 3 ? rgba(1.0f, 0.55f, 0.05f, 1) : rgba(0.95f, 0.15f, 0.15f, 1);
    dl->AddRectFilled(ImVec2(x_of(i - 0.5), p1.y - 3 * scale), ImVec2(x_of(i + 0.5), p1.y), col);
  }
  const std::vector<Keyframe>& keys = c.editor.scene().keyframes;
  for (const Keyframe& k : keys) {
    const float x = x_of(c.solver.frame_at(k.time));
    const float s = 5 * scale;
    dl->AddTriangleFilled(ImVec2(x - s, p0.y), ImVec2(x + s, p0.y), ImVec2(x, p0.y + s * 1.4f), rgba(1, 0.6f, 0.1f));
  }
  // Each interval's timing (the one leaving its first keyframe), written in the scrubber
  // between its keyframes where it fits; a right click on an interval picks another.
  const float text_y = 0.5f * (p0.y + p1.y) - 0.5f * ImGui::GetTextLineHeight();
  int hovered_interval = -1;
  const float mouse_x = ImGui::GetIO().MousePos.x;
  for (size_t k = 0; k + 1 < keys.size(); ++k) {
    const float xa = x_of(c.solver.frame_at(keys[k].time)), xb = x_of(c.solver.frame_at(keys[k + 1].time));
    const char* name = to_string(keys[k].timing);
    const float w = ImGui::CalcTextSize(name).x;
    if (xb - xa > w + 24 * scale) dl->AddText(ImVec2(0.5f * (xa + xb) - 0.5f * w, text_y), rgba(0.75f, 0.75f, 0.8f, 0.9f), name);
    if (mouse_x >= xa && mouse_x < xb) hovered_interval = static_cast<int>(k);
  }
  ImGuiStorage* store = ImGui::GetStateStorage();
  const ImGuiID picked_id = ImGui::GetID("##interval_picked");
  if (hovered_interval >= 0 && ImGui::IsMouseHoveringRect(ImVec2(p0.x, p0.y), p1) && ImGui::IsMouseClicked(ImGuiMouseButton_Right)) {
    store->SetInt(picked_id, hovered_interval);
    ImGui::OpenPopup("##interval_timing");
  }
  if (ImGui::BeginPopup("##interval_timing")) {
    const int k = store->GetInt(picked_id, -1);
    if (k >= 0 && k + 1 < static_cast<int>(keys.size())) {
      ImGui::TextDisabled("timing of keyframes %d -> %d", k, k + 1);
      static const KeyTiming modes[] = {KeyTiming::Linear, KeyTiming::Smooth, KeyTiming::Ease, KeyTiming::Hold};
      const KeyTiming now = keys[static_cast<size_t>(k)].timing;
      for (KeyTiming m : modes)
        if (ImGui::Selectable(to_string(m), m == now) && m != now) {
          req.timing_keyframe = k;
          req.timing = m;
        }
    } else {
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
  ImGui::End();
  return req;
}

void draw_help(Overlays& overlays, const View& view) {
  if (!overlays.help) return;
  ImGui::SetNextWindowPos(ImVec2(view.size().x / 2, view.size().y / 2), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowBgAlpha(0.94f);
  ImGui::Begin("Keys (H to close)", &overlays.help,
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
      {"N", "texture filter: nearest texels / linear"},
      {"H  F1  ?", "this help"},
      {"F", "fit the view; wheel zooms, middle-drag pans"},
      {"drag a handle", "pose the keyframe (at a keyframe)"},
      {"right click the timeline", "timing of that keyframe interval"},
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
  ImGui::End();
}

}  // namespace hsi::viewer
