// The viewer's view: layout of the viewport, fit, zoom and pan.
#include "view.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hsi::viewer {

Framing frame_keyframes(const BasisRows& probe, const std::vector<HarmonicMap>& maps) {
  // The view frames every keyframe's image (so playback does not jump); the colour
  // map spans the keyframes' largest distortion.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Framing out;
  out.box = {cd(kInf, kInf), cd(-kInf, -kInf)};
  double kappa = 1;
  for (const HarmonicMap& m : maps) {
    const MapValues v = evaluate_map(probe, m);
    for (Eigen::Index i = 0; i < v.f.size(); ++i) {
      const cd z = v.f(i);
      out.box.lo = {std::min(out.box.lo.real(), z.real()), std::min(out.box.lo.imag(), z.imag())};
      out.box.hi = {std::max(out.box.hi.real(), z.real()), std::max(out.box.hi.imag(), z.imag())};
      const double a = std::abs(v.f_z(i)), b = std::abs(v.fzbar_conj(i));
      if (a > b) kappa = std::max(kappa, (a + b) / (a - b));
    }
  }
  // Some room around it: poses between keyframes may reach a little further.
  const cd pad = 0.06 * (out.box.hi - out.box.lo);
  out.box.lo -= cd(pad.real(), pad.imag());
  out.box.hi += cd(pad.real(), pad.imag());
  out.dist_hi = compute::round_distortion_hi(std::max(kappa * 1.1, 1.2));
  return out;
}

void View::layout() {
  ImGuiIO& io = ImGui::GetIO();
  const float side = std::min(340.0f * scale_, 0.4f * io.DisplaySize.x);
  const float bottom = std::min(ImGui::GetFrameHeightWithSpacing() * 2 + ImGui::GetStyle().WindowPadding.y * 2 + 8 * scale_,
                                0.4f * io.DisplaySize.y);
  pos_ = ImVec2(0, 0);
  size_ = ImVec2(std::max(1.0f, io.DisplaySize.x - side), std::max(1.0f, io.DisplaySize.y - bottom));
  fb_scale_ = io.DisplayFramebufferScale;
}

bool View::contains(ImVec2 m) const {
  return m.x >= pos_.x && m.y >= pos_.y && m.x < pos_.x + size_.x && m.y < pos_.y + size_.y;
}

int View::pixel_width() const { return std::max(16, static_cast<int>(std::lround(size_.x * fb_scale_.x))); }
int View::pixel_height() const { return std::max(16, static_cast<int>(std::lround(size_.y * fb_scale_.y))); }

double View::fitted_pixels_per_unit() const {
  return compute::View::fit(box_, width_, height_, 16.0 * scale_ * fb_scale_.x).pixels_per_unit;
}

const compute::View& View::update_camera(int width, int height) {
  width_ = width;
  height_ = height;
  camera_ = compute::View::fit(box_, width, height, 16.0 * scale_ * fb_scale_.x);
  camera_.pixels_per_unit *= zoom_;
  camera_.world_center += pan_;
  return camera_;
}

void View::handle_mouse(bool in_vp) {
  const ImGuiIO& io = ImGui::GetIO();
  const ImVec2 m = io.MousePos;
  // Zoom about the mouse, pan with the middle button.
  if (in_vp && io.MouseWheel != 0 && width_ > 0) {
    const cd before = to_world(m);
    zoom_ = std::clamp(zoom_ * std::pow(1.15, io.MouseWheel), 0.1, 50.0);
    camera_.pixels_per_unit = fitted_pixels_per_unit() * zoom_;
    const cd after = to_world(m);
    pan_ += before - after;
    camera_.world_center += before - after;
  }
  if (in_vp && ImGui::IsMouseClicked(ImGuiMouseButton_Middle)) middle_drag_ = true;
  if (!ImGui::IsMouseDown(ImGuiMouseButton_Middle)) middle_drag_ = false;
  if (middle_drag_ && (io.MouseDelta.x != 0 || io.MouseDelta.y != 0)) {
    const cd d(io.MouseDelta.x * fb_scale_.x / camera_.pixels_per_unit, -io.MouseDelta.y * fb_scale_.y / camera_.pixels_per_unit);
    pan_ -= d;
    camera_.world_center -= d;
  }
}

cd View::to_world(ImVec2 s) const {
  const double px = (s.x - pos_.x) * fb_scale_.x, py = (s.y - pos_.y) * fb_scale_.y;
  return {camera_.world_center.real() + (px - camera_.pixel_center.real()) / camera_.pixels_per_unit,
          camera_.world_center.imag() - (py - camera_.pixel_center.imag()) / camera_.pixels_per_unit};
}

ImVec2 View::to_screen(cd w) const {
  const cd p = camera_.to_pixel(w);
  return {pos_.x + static_cast<float>(p.real() / fb_scale_.x), pos_.y + static_cast<float>(p.imag() / fb_scale_.y)};
}

}  // namespace hsi::viewer
