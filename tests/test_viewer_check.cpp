// Checks a screenshot of hsi-viewer (tests/test_viewer.cmake runs the viewer under
// Xvfb + lavapipe, then this):
//   hsi_viewer_check SHOT.png GOLDEN.png TEXTURE.png FRAME
// SHOT.png.json (written by the viewer) says where the viewport is and what it shows.
//  - the window has the size asked for, and the frame is FRAME, certified;
//  - the viewport is not blank: the shape covers a sensible part of it;
//  - the shape's pixels have the texture's colours (a colour histogram of the texture),
//    and the right ones where they are (bar_holes: blue on the left, yellow on the right);
//  - the viewport matches GOLDEN.png within a perceptual tolerance (mean absolute
//    difference and the fraction of pixels off by more than 48/255), as the
//    renderer's goldens are compared. HSI_UPDATE_GOLDEN=1 writes GOLDEN.png instead.
// Exit 0 when all hold; 1 with a message naming what does not.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hsi/png.h"

using hsi::RgbaImage;

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  std::printf("%s %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}

RgbaImage crop(const RgbaImage& img, int x0, int y0, int w, int h) {
  RgbaImage out(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = img.at(x0 + x, y0 + y);
      std::copy(p, p + 4, out.at(x, y));
    }
  return out;
}

// hsi_viewer_check --differ A.png B.png: the two screenshots' viewports (A.png.json's)
// differ in at least `min_pixels` pixels (the texture filter toggled, say).
int differ(const std::filesystem::path& a_path, const std::filesystem::path& b_path) {
  const RgbaImage a = hsi::read_png(a_path), b = hsi::read_png(b_path);
  std::ifstream meta_file(a_path.string() + ".json");
  const auto vp = nlohmann::json::parse(meta_file).at("viewport");
  const int vx = vp[0], vy = vp[1], vw = vp[2], vh = vp[3];
  check(a.width == b.width && a.height == b.height, "the two screenshots have one size");
  if (failures) return 1;
  size_t changed = 0;
  for (int y = vy; y < vy + vh; ++y)
    for (int x = vx; x < vx + vw; ++x) changed += !std::equal(a.at(x, y), a.at(x, y) + 3, b.at(x, y));
  constexpr size_t min_pixels = 100;
  check(changed >= min_pixels, std::to_string(changed) + " viewport pixels differ between " + a_path.string() + " and " +
                                   b_path.string() + " (expected at least " + std::to_string(min_pixels) + ")");
  return failures ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--differ") return differ(argv[2], argv[3]);
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s SHOT.png GOLDEN.png TEXTURE.png FRAME\n", argv[0]);
    return 2;
  }
  const std::filesystem::path shot_path = argv[1], golden_path = argv[2], texture_path = argv[3];
  const int expect_frame = std::atoi(argv[4]);
  try {
    const RgbaImage shot = hsi::read_png(shot_path);
    std::ifstream meta_file(shot_path.string() + ".json");
    check(static_cast<bool>(meta_file), "the viewer wrote " + shot_path.string() + ".json");
    if (!meta_file) return 1;
    const nlohmann::json meta = nlohmann::json::parse(meta_file);
    check(meta.at("width") == shot.width && meta.at("height") == shot.height,
          "screenshot size " + std::to_string(shot.width) + " x " + std::to_string(shot.height) + " as recorded");
    check(meta.at("frame") == expect_frame, "the screenshot shows frame " + meta.at("frame").dump() + " (expected " +
                                                std::to_string(expect_frame) + ")");
    check(meta.at("certified") == true, "the frame is certified");
    const auto vp = meta.at("viewport");
    const int vx = vp[0], vy = vp[1], vw = vp[2], vh = vp[3];
    check(vx >= 0 && vy >= 0 && vw > 64 && vh > 64 && vx + vw <= shot.width && vy + vh <= shot.height,
          "viewport [" + std::to_string(vx) + ", " + std::to_string(vy) + ", " + std::to_string(vw) + ", " +
              std::to_string(vh) + "] inside the window");
    if (failures) return 1;
    const RgbaImage view = crop(shot, vx, vy, vw, vh);

    // The background is the corner's colour; the shape is what differs from it.
    const uint8_t* bg = view.at(vw - 2, vh - 2);
    auto is_bg = [&](const uint8_t* p) {
      return std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) < 12;
    };
    check(bg[0] > 200 && bg[1] > 200 && bg[2] > 200, "the viewport's background is light (" + std::to_string(bg[0]) + ", " +
                                                         std::to_string(bg[1]) + ", " + std::to_string(bg[2]) + ")");
    // The texture's colours, quantised to 16 levels per channel.
    const RgbaImage tex = hsi::read_png(texture_path);
    std::vector<bool> palette(4096, false);
    auto bin = [](const uint8_t* p) { return (p[0] / 16) * 256 + (p[1] / 16) * 16 + p[2] / 16; };
    for (int y = 0; y < tex.height; ++y)
      for (int x = 0; x < tex.width; ++x)
        if (tex.at(x, y)[3] > 0) palette[static_cast<size_t>(bin(tex.at(x, y)))] = true;
    auto near_palette = [&](const uint8_t* p) {  // its bin or a neighbouring one (texture filtering blends)
      const int r = p[0] / 16, g = p[1] / 16, b = p[2] / 16;
      for (int dr = -1; dr <= 1; ++dr)
        for (int dg = -1; dg <= 1; ++dg)
          for (int db = -1; db <= 1; ++db) {
            const int R = r + dr, G = g + dg, B = b + db;
            if (R >= 0 && R < 16 && G >= 0 && G < 16 && B >= 0 && B < 16 && palette[static_cast<size_t>(R * 256 + G * 16 + B)])
              return true;
          }
      return false;
    };
    size_t shape = 0, textured = 0;
    for (int y = 0; y < vh; ++y)
      for (int x = 0; x < vw; ++x) {
        const uint8_t* p = view.at(x, y);
        if (is_bg(p)) continue;
        ++shape;
        textured += near_palette(p);
      }
    const double coverage = static_cast<double>(shape) / (static_cast<double>(vw) * vh);
    const double tex_fraction = shape ? static_cast<double>(textured) / static_cast<double>(shape) : 0;
    char buf[160];
    std::snprintf(buf, sizeof buf, "the shape covers %.1f%% of the viewport (expected 10%%..85%%)", 100 * coverage);
    check(coverage > 0.10 && coverage < 0.85, buf);
    std::snprintf(buf, sizeof buf, "%.1f%% of the shape's pixels have the texture's colours (expected >= 85%%)", 100 * tex_fraction);
    check(tex_fraction >= 0.85, buf);
    // Where: bar_holes' texture runs from blue (left) to yellow (right), and the map
    // keeps left on the left: the shape's left fifth is blue, its right fifth yellow.
    int xmin = vw, xmax = -1;
    for (int y = 0; y < vh; ++y)
      for (int x = 0; x < vw; ++x)
        if (!is_bg(view.at(x, y))) {
          xmin = std::min(xmin, x);
          xmax = std::max(xmax, x);
        }
    double left[3] = {0, 0, 0}, right[3] = {0, 0, 0};
    size_t nl = 0, nr = 0;
    for (int y = 0; y < vh; ++y)
      for (int x = 0; x < vw; ++x) {
        const uint8_t* p = view.at(x, y);
        if (is_bg(p)) continue;
        const bool l = x < xmin + (xmax - xmin) / 5, r = x > xmax - (xmax - xmin) / 5;
        for (int c = 0; c < 3; ++c) (l ? left[c] : right[c]) += (l || r) ? p[c] : 0;
        nl += l;
        nr += r;
      }
    for (int c = 0; c < 3; ++c) {
      left[c] /= static_cast<double>(std::max<size_t>(nl, 1));
      right[c] /= static_cast<double>(std::max<size_t>(nr, 1));
    }
    std::snprintf(buf, sizeof buf, "the shape's left fifth is blue (mean RGB %.0f %.0f %.0f), its right fifth yellow (%.0f %.0f %.0f)",
                  left[0], left[1], left[2], right[0], right[1], right[2]);
    check(nl > 0 && nr > 0 && left[2] > left[0] + 40 && right[0] > right[2] + 40 && right[1] > right[2] + 40, buf);

    if (const char* u = std::getenv("HSI_UPDATE_GOLDEN"); u && *u && std::string(u) != "0") {
      hsi::write_png(golden_path, view);
      std::printf("HSI_UPDATE_GOLDEN: wrote %s (look at it before committing)\n", golden_path.string().c_str());
      return failures ? 1 : 0;
    }
    check(std::filesystem::exists(golden_path), "golden " + golden_path.string() + " exists (HSI_UPDATE_GOLDEN=1 writes it)");
    if (failures) return 1;
    const RgbaImage ref = hsi::read_png(golden_path);
    check(ref.width == vw && ref.height == vh, "the golden is " + std::to_string(ref.width) + " x " + std::to_string(ref.height) +
                                                   ", the viewport " + std::to_string(vw) + " x " + std::to_string(vh));
    if (failures) return 1;
    double sum = 0;
    size_t outliers = 0;
    RgbaImage diff(vw, vh);
    for (int y = 0; y < vh; ++y)
      for (int x = 0; x < vw; ++x) {
        const uint8_t *p = view.at(x, y), *q = ref.at(x, y);
        int m = 0;
        for (int c = 0; c < 3; ++c) {
          const int d = std::abs(int(p[c]) - int(q[c]));
          sum += d;
          m = std::max(m, d);
        }
        outliers += m > 48;
        uint8_t* o = diff.at(x, y);
        o[0] = o[1] = o[2] = static_cast<uint8_t>(255 - std::min(255, 4 * m));
        o[3] = 255;
      }
    const double mean = sum / (3.0 * vw * vh), out = static_cast<double>(outliers) / (static_cast<double>(vw) * vh);
    std::snprintf(buf, sizeof buf, "matches the golden: mean |diff| %.3f (<= 2), %.3f%% pixels off by > 48 (<= 1%%)", mean, 100 * out);
    check(mean <= 2.0 && out <= 0.01, buf);
    if (mean > 2.0 || out > 0.01) {
      const std::filesystem::path d = shot_path.parent_path() / (shot_path.stem().string() + "_diff.png");
      hsi::write_png(d, diff);
      std::printf("     the difference is in %s\n", d.string().c_str());
    }
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    return 1;
  }
  return failures ? 1 : 0;
}
