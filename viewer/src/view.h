// The viewer's view: where the viewport sits in the window, the camera that frames every
// keyframe's image (fit), zoom about the mouse and pan, and the world ↔ screen maps.
#pragma once

#include <imgui.h>

#include <vector>

#include "hsi/basis.h"
#include "hsi/compute/renderer.h"
#include "hsi/harmonic_map.h"

namespace hsi::viewer {

// What the view frames and the colour map spans, from the keyframes' maps.
struct Framing {
  BoundingBox box{};    // every keyframe's image, with some room
  double dist_hi = 2;   // the distortion colour map's upper end
};
// probe: basis rows (C and D) at points of the shape's boundary.
Framing frame_keyframes(const BasisRows& probe, const std::vector<HarmonicMap>& maps);

class View {
 public:
  explicit View(float content_scale) : scale_(content_scale) {}

  float scale() const { return scale_; }  // content scale (high DPI)
  // The viewport from ImGui's display: left of the side panel, above the timeline.
  void layout();
  ImVec2 pos() const { return pos_; }
  ImVec2 size() const { return size_; }
  ImVec2 fb_scale() const { return fb_scale_; }
  bool contains(ImVec2 screen) const;
  // The viewport's size in framebuffer pixels (at least 16 × 16): the render size.
  int pixel_width() const;
  int pixel_height() const;

  void set_box(const BoundingBox& box) { box_ = box; }
  // The camera for a width × height image: the box fitted, then zoom and pan.
  const compute::View& update_camera(int width, int height);
  const compute::View& camera() const { return camera_; }

  // Wheel zoom about the mouse and middle-button pan (once a camera exists).
  void handle_mouse(bool in_viewport);
  void fit() {  // F: back to the fitted view
    zoom_ = 1;
    pan_ = 0;
  }

  cd to_world(ImVec2 screen) const;
  ImVec2 to_screen(cd world) const;

 private:
  double fitted_pixels_per_unit() const;

  float scale_ = 1;
  ImVec2 pos_{0, 0}, size_{1, 1};  // viewport in window points
  ImVec2 fb_scale_{1, 1};
  BoundingBox box_{};
  double zoom_ = 1;
  cd pan_{0, 0};
  compute::View camera_;
  int width_ = 0, height_ = 0;  // of the last camera (0: none yet)
  bool middle_drag_ = false;
};

}  // namespace hsi::viewer
