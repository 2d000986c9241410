// hsi_eval_check: an evaluation of a map independent of the engine's basis code, to
// check `hsi eval` against (ctest cli_authoring). The Cauchy coordinates are written
// out here from math.md §2, the derivatives taken by central differences of f, and
// "inside" by its own even-odd ray test; only the file readers are the engine's.
//   hsi_eval_check points SCENE N OUT.csv           N random points over the shape's box (fixed seed)
//   hsi_eval_check check EVAL.json SCENE --keyframe K
//   hsi_eval_check check EVAL.json SCENE --frames F.hsif --frame I
// Exits 0 when every value agrees (f to 1e-10 of the size, f_z and f_zbar to 1e-6, σ
// likewise), 1 otherwise, printing the worst differences.
#include <cmath>
#include <complex>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hsi/frames_io.h"
#include "hsi/scene_io.h"

using cd = std::complex<double>;

namespace {

bool in_loop(const std::vector<cd>& loop, cd p) {
  bool in = false;
  for (size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
    const cd a = loop[i], b = loop[j];
    if ((a.imag() > p.imag()) != (b.imag() > p.imag()) &&
        p.real() < (b.real() - a.real()) * (p.imag() - a.imag()) / (b.imag() - a.imag()) + a.real())
      in = !in;
  }
  return in;
}

// f(w) = Σ C_j φ_j + conj(Σ C_j ψ_j) with C_j of math.md §2 and log|w − ρ_i| per hole.
cd f_at(const hsi::Cage& cage, const hsi::HarmonicMap& m, cd w) {
  const cd two_pi_i(0, 2 * std::numbers::pi);
  cd a = 0, b = 0;
  int j0 = 0;
  for (const auto& loop : cage.loops) {
    const int n = static_cast<int>(loop.size());
    for (int j = 0; j < n; ++j) {
      const cd zp = loop[static_cast<size_t>((j + n - 1) % n)], z = loop[static_cast<size_t>(j)],
               zn = loop[static_cast<size_t>((j + 1) % n)];
      const cd A = z - zp, An = zn - z, Bp = zp - w, B = z - w, Bn = zn - w;
      const cd C = (Bn / An * std::log(Bn / B) - Bp / A * std::log(B / Bp)) / two_pi_i;
      a += C * m.phi(j0 + j);
      b += C * m.psi(j0 + j);
    }
    j0 += n;
  }
  for (size_t h = 0; h < cage.hole_points.size(); ++h) {
    const double L = std::log(std::abs(w - cage.hole_points[h]));
    a += L * m.phi(j0 + static_cast<int>(h));
    b += L * m.psi(j0 + static_cast<int>(h));
  }
  return a + std::conj(b);
}

cd pair(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>()}; }

int usage() {
  std::fprintf(stderr, "usage: hsi_eval_check points SCENE N OUT.csv | check EVAL.json SCENE (--keyframe K | --frames F --frame I)\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> a(argv + 1, argv + argc);
  if (a.size() == 4 && a[0] == "points") {
    const hsi::Scene s = hsi::load_scene(a[1]);
    const hsi::BoundingBox bb = hsi::bounding_box(s.shape);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.05, 1.05);
    std::ofstream out(a[3]);
    out << "x,y\n";
    out.precision(17);
    for (int i = 0; i < std::stoi(a[2]); ++i)
      out << bb.lo.real() + u(rng) * (bb.hi.real() - bb.lo.real()) << "," << bb.lo.imag() + u(rng) * (bb.hi.imag() - bb.lo.imag()) << "\n";
    return out ? 0 : 1;
  }
  if (a.size() != 5 && a.size() != 7) return usage();
  if (a[0] != "check") return usage();
  std::ifstream eval_file(a[1]);
  const nlohmann::json e = nlohmann::json::parse(eval_file);
  const hsi::Scene scene = hsi::load_scene(a[2]);
  hsi::Cage cage;
  hsi::HarmonicMap map;
  if (a[3] == "--keyframe") {
    const auto& k = scene.keyframes.at(std::stoul(a[4]));
    if (!scene.cage || !k.coefficients) {
      std::fprintf(stderr, "the scene must hold the keyframe's coefficients (run hsi keyframes first)\n");
      return 2;
    }
    cage = *scene.cage;
    map = *k.coefficients;
  } else if (a[3] == "--frames" && a.size() == 7) {
    const hsi::FrameFile f = hsi::read_frames(a[4]);
    cage = f.cage;
    map = f.frames.at(std::stoul(a[6])).map;
  } else {
    return usage();
  }
  const hsi::BoundingBox bb = hsi::bounding_box(scene.shape);
  const double size = bb.diagonal(), h = 1e-5 * size;
  double worst_f = 0, worst_d = 0, worst_s = 0;
  int inside = 0, flag_errors = 0;
  for (const nlohmann::json& p : e.at("points")) {
    const cd w(p.at("x").get<double>(), p.at("y").get<double>());
    bool in = in_loop(scene.shape.outer, w);
    for (const auto& hole : scene.shape.holes) in = in && !in_loop(hole, w);
    if (in != p.at("inside").get<bool>()) {
      // A point a hair from the boundary may fall either way.
      if (hsi::boundary_distance(scene.shape, w) > 1e-9 * size) ++flag_errors;
      continue;
    }
    if (!in) {
      if (p.contains("f")) ++flag_errors;  // no values outside the shape
      continue;
    }
    ++inside;
    const cd f = f_at(cage, map, w);
    const cd fx = (f_at(cage, map, w + h) - f_at(cage, map, w - h)) / (2 * h);
    const cd fy = (f_at(cage, map, w + cd(0, h)) - f_at(cage, map, w - cd(0, h))) / (2 * h);
    const cd fz = 0.5 * (fx - cd(0, 1) * fy), fzbar = 0.5 * (fx + cd(0, 1) * fy);
    worst_f = std::max(worst_f, std::abs(f - pair(p.at("f"))) / size);
    worst_d = std::max({worst_d, std::abs(fz - pair(p.at("f_z"))), std::abs(fzbar - pair(p.at("f_zbar")))});
    worst_s = std::max({worst_s, std::abs(std::abs(fz) + std::abs(fzbar) - p.at("sigma1").get<double>()),
                        std::abs(std::abs(fz) - std::abs(fzbar) - p.at("sigma2").get<double>())});
  }
  std::printf("%d points inside; worst |f - f_ref| / size %.3g, |f_z|, |f_zbar| %.3g, sigma %.3g; %d wrong inside flags\n", inside,
              worst_f, worst_d, worst_s, flag_errors);
  return worst_f <= 1e-10 && worst_d <= 1e-6 && worst_s <= 1e-6 && flag_errors == 0 && inside > 0 ? 0 : 1;
}
