// The C API's handle types, shared by c_api.cpp and c_api_render.cpp (private).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "hsi/hsi.h"
#include "hsi/runtime/backend.h"
#include "hsi/scene_sequence.h"

struct hsi_scene {
  hsi::Scene scene;
  std::shared_ptr<const hsi::ShapeSetup> setup;  // made on first need; replaced, never changed
  int samples = 0;
  double hessian_ratio = 0;
};

struct hsi_interpolator {
  std::shared_ptr<const hsi::Scene> scene;
  std::shared_ptr<const hsi::ShapeSetup> setup;  // outlives `interp`, which refers to it
  std::unique_ptr<hsi::Interpolator> interp;
  hsi::runtime::BackendChoice backend;  // the Newton core interp runs on, and why
  Eigen::VectorXd warm;
};

struct hsi_sequence {
  std::shared_ptr<const hsi::Scene> scene;
  hsi::SceneSequence seq;
  std::shared_ptr<void> render_cache;  // c_api_render.cpp's renderer, kept between calls
};

namespace hsi::capi {

// Thrown inside the API for a status other than INPUT/INTERNAL; turned into the code.
struct ApiError {
  hsi_status status;
  std::string message;
};

#ifdef HSI_CAPI_RENDER
bool render_available(std::string* why);
void render_frame(hsi_sequence& sequence, uint32_t frame, const hsi_render_options& options, uint8_t* rgba, size_t row_stride);
#endif

}  // namespace hsi::capi
