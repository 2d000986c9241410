// libFuzzer harness: baked playback files (.hsib, the C runtime's hsib_open_memory,
// then queries, binding and evaluation on what it accepts). Each input is tried as
// it is and once more with every checksum recomputed from the sizes its header
// announces, so that the fuzzer reaches the parsing behind the CRC-32 checks.
// Any input must open or be refused with a status and a message; a crash, a
// sanitizer report or an accepted file that cannot be played is a finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "hsi/baked_runtime.h"

namespace {

uint32_t rd32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
uint64_t rd64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
void wr32(uint8_t* p, uint32_t v) { std::memcpy(p, &v, 4); }

// Recomputes the header, static-section and frame checksums where they fit (the
// header's size and the place of its own checksum depend on the version: 1 or 2).
void fix_checksums(std::vector<uint8_t>& b) {
  if (b.size() < 8) return;
  const uint32_t H = rd32(b.data() + 4) == 1 ? HSIB_HEADER_SIZE_V1 : HSIB_HEADER_SIZE;
  if (b.size() < H) return;
  const uint64_t static_bytes = rd64(b.data() + 80);
  const uint32_t F = rd32(b.data() + 40), S = rd32(b.data() + 44);
  if (static_bytes <= b.size() - H) {
    wr32(b.data() + 88, hsib_crc32(b.data() + H, static_bytes));
    const uint64_t frames_at = H + static_bytes;
    if (S >= 8)
      for (uint64_t f = 0; f < F && frames_at + (f + 1) * S <= b.size(); ++f) {
        uint8_t* fr = b.data() + frames_at + f * S;
        wr32(fr + S - 4, hsib_crc32(fr, S - 4));
      }
  }
  wr32(b.data() + H - 4, hsib_crc32(b.data(), H - 4));
}

void exercise(const uint8_t* data, size_t size) {
  hsib_sequence* s = nullptr;
  char error[256];
  std::memset(error, 'x', sizeof error);
  const hsib_status st = hsib_open_memory(data, size, &s, error, sizeof error);
  if (st != HSIB_OK) {
    // Refused: no sequence, and a message that names the problem.
    if (s != nullptr || std::memchr(error, '\0', sizeof error) == nullptr || error[0] == '\0') std::abort();
    return;
  }
  hsib_info info;
  hsib_get_info(s, &info);
  for (uint32_t f = 0; f < info.frame_count; ++f) {
    double t;
    uint32_t flags;
    if (hsib_frame_info(s, f, &t, &flags) != HSIB_OK || !std::isfinite(t)) std::abort();
    // An opened file's stop word was checked: a known reason, consistent with flag 4, or not recorded.
    uint32_t stop = 0;
    if (hsib_frame_stop(s, f, &stop) != HSIB_OK || (stop >= HSIB_STOP_COUNT && stop != HSIB_STOP_NOT_RECORDED) ||
        ((stop == HSIB_STOP_CONVERGED) != ((flags & HSIB_FRAME_CONVERGED) != 0)))
      std::abort();
  }
  (void)hsib_frame_at_time(s, 0.5 * (info.t_begin + info.t_end));
  // A few rest vertices around the recorded bounding box: some inside the cage,
  // some not; both outcomes are fine, a crash is not.
  const double x0 = info.bbox[0], y0 = info.bbox[1], x1 = info.bbox[2], y1 = info.bbox[3];
  std::vector<float> xy;
  for (double u : {0.25, 0.5, 0.75})
    for (double v : {0.3, 0.5, 0.7}) {
      xy.push_back(static_cast<float>(x0 + u * (x1 - x0)));
      xy.push_back(static_cast<float>(y0 + v * (y1 - y0)));
    }
  for (size_t i = 0; i < xy.size() / 2; ++i) {
    hsib_binding* b = nullptr;
    if (hsib_bind(s, xy.data() + 2 * i, 1, 0, &b, error, sizeof error) != HSIB_OK) continue;
    float out[2];
    if (info.frame_count > 0) {
      if (hsib_evaluate(b, 0, out, 0) != HSIB_OK) std::abort();
      if (hsib_evaluate(b, info.frame_count - 1, out, 0) != HSIB_OK) std::abort();
    }
    hsib_unbind(b);
  }
  if (info.frame_count > 0) {
    std::vector<float> w(2 * static_cast<size_t>(info.row_length));
    float c[2];
    if (hsib_frame_weights(s, 0, w.data(), c) != HSIB_OK) std::abort();
  }
  // Version 2: the stored mesh binds (vertices clamped where outside the cage), blends
  // at any time play, and the GPU data fill; regions of the vertices are defined.
  hsib_mesh mesh;
  if (info.frame_count > 0 && hsib_get_mesh(s, &mesh) == HSIB_OK && mesh.vertex_count <= 4096) {
    std::vector<uint8_t> region(mesh.vertex_count);
    hsib_bind_options o{};
    o.outside = HSIB_OUTSIDE_CLAMP;
    o.vertex_region = region.data();
    hsib_binding* b = nullptr;
    // Every other input also binds derivative rows and plays the distortion.
    const uint32_t flags = (size & 1u) ? HSIB_BIND_DERIVATIVES : 0u;
    if (hsib_bind_flags(s, mesh.xy, mesh.vertex_count, 0, &o, flags, &b, error, sizeof error) == HSIB_OK) {
      for (uint8_t r : region)
        if (r > HSIB_REGION_SHAPE) std::abort();
      std::vector<float> out(2 * static_cast<size_t>(mesh.vertex_count));
      for (double u : {-0.5, 0.0, 0.37, 0.5, 1.0, 2.0})
        for (const hsib_playback m : {HSIB_PLAY_NEAREST, HSIB_PLAY_CERTIFIED_STEPS, HSIB_PLAY_BLEND}) {
          const hsib_blend bl = hsib_blend_at_time(s, info.t_begin + u * (info.t_end - info.t_begin), m);
          if (hsib_evaluate_blend(b, &bl, out.data(), 0) != HSIB_OK) std::abort();
          if ((hsib_evaluate_blend_distortion(b, &bl, out.data(), 0) == HSIB_OK) != (flags != 0)) std::abort();
        }
      std::vector<float> derivatives(hsib_gpu_derivative_rows_floats(b, 64));
      if ((hsib_gpu_derivative_rows(b, 64, derivatives.data()) == HSIB_OK) != (flags != 0)) std::abort();
      std::vector<float> texels(hsib_gpu_rows_floats(b, 64));
      if (hsib_gpu_rows(b, 64, texels.data()) != HSIB_OK) std::abort();
      std::vector<float> u(4 * (2 + static_cast<size_t>(info.row_length)));
      const hsib_blend first{0, 0, 0.0f, 0};
      if (hsib_gpu_uniforms(s, &first, u.data()) != HSIB_OK) std::abort();
      hsib_unbind(b);
    }
    for (uint32_t t = 0; t < mesh.triangle_count && t < 64; ++t)
      if (mesh.triangles[3 * t] >= mesh.vertex_count) std::abort();
  }
  hsib_close(s);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  exercise(data, size);
  std::vector<uint8_t> fixed(data, data + size);
  fix_checksums(fixed);
  exercise(fixed.data(), fixed.size());
  return 0;
}
