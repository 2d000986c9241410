// Benchmark of baked playback (hsi/baked_runtime.h) on render meshes of 1k, 10k and
// 100k vertices (the shape's triangulation): the runtime's one-time precomputation
// of basis rows and its per-frame cost, against, in the same run, the C++ engine's
// evaluate_map with precomputed basis rows (complex C·φ + conj(C·ψ)) and against
// the alternative layout that stores per-vertex rows over the reduced coefficients
// (2 × dim floats per vertex instead of R). One thread throughout. Timings only.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <omp.h>

#include "bench_scenes.h"
#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/triangulate.h"

using namespace hsi;

namespace {

using Clock = std::chrono::steady_clock;
double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

// Repeats fn until ~min_ms have passed; returns µs per call.
template <class F>
double time_per_call(F&& fn, double min_ms = 300) {
  fn();  // warm
  int calls = 0;
  const auto t0 = Clock::now();
  do {
    fn();
    ++calls;
  } while (us_since(t0) < 1000 * min_ms);
  return us_since(t0) / calls;
}

// The reduced-row alternative: per vertex two float rows of length dim (x and y of f
// over the reduced coefficients), in panels of 64 like the runtime.
struct ReducedRows {
  int dim = 0;
  size_t vertices = 0;
  std::vector<float> rows;  // panels × 2 × dim × 64
  void apply(const std::vector<float>& x, std::vector<float>& out) const {
    const size_t panels = (vertices + 63) / 64;
    for (size_t p = 0; p < panels; ++p) {
      float ax[64] = {}, ay[64] = {};
      const float* P = rows.data() + p * 2 * static_cast<size_t>(dim) * 64;
      for (int d = 0; d < dim; ++d) {
        const float xd = x[static_cast<size_t>(d)];
        const float* rx = P + (2 * static_cast<size_t>(d)) * 64;
        const float* ry = rx + 64;
        for (int i = 0; i < 64; ++i) {
          ax[i] += rx[i] * xd;
          ay[i] += ry[i] * xd;
        }
      }
      for (size_t i = 0; i < 64 && p * 64 + i < vertices; ++i) {
        out[2 * (p * 64 + i)] = ax[i];
        out[2 * (p * 64 + i) + 1] = ay[i];
      }
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Baked playback: per-frame cost of the runtime vs direct evaluation, 1k/10k/100k vertices"};
  std::string scene_path = std::string(HSI_ASSETS_DIR) + "/bar_holes.json";
  std::vector<int> sizes{1000, 10000, 100000};
  app.add_option("--scene", scene_path, "Scene file")->capture_default_str();
  app.add_option("--vertices", sizes, "Mesh sizes (approximate vertex counts)");
  CLI11_PARSE(app, argc, argv);
  omp_set_num_threads(1);

  bench::Loaded L = bench::load(scene_path, 2000, 0.2);
  const ShapeSetup& setup = *L.setup;
  FrameFile ff;
  ff.cage = setup.cage;
  for (size_t k = 0; k < L.maps.size(); ++k) ff.frames.push_back({L.times[k], true, true, true, 0, 2.0, L.maps[k]});
  const std::string bytes = encode_baked(setup.shape, ff);
  hsib_sequence* seq = nullptr;
  char error[256];
  if (hsib_open_memory(bytes.data(), bytes.size(), &seq, error, sizeof error) != HSIB_OK) {
    std::fprintf(stderr, "bench_baked: %s\n", error);
    return 1;
  }
  hsib_info info;
  hsib_get_info(seq, &info);
  const MapSpace map_gauge(setup.cage, Gauge::Map);
  std::printf("scene %s: cage %d vertices, %d holes; row length R = %u, reduced coefficients D = %u (%u bytes per frame, f32)\n",
              L.name.c_str(), setup.cage.vertex_count(), setup.cage.hole_count(), info.row_length, info.coefficient_count,
              48 + 4 * info.coefficient_count + 4);
  std::printf("one thread; %s\n\n", "per-frame times average many frames cycling over the keyframes");
  std::printf("| vertices | precompute ms (runtime) | precompute ms (C++ basis) | frame µs (runtime, R=%u) | frame µs (C++ evaluate_map) | "
              "frame µs (reduced rows, 2x%d) | C++ / runtime | reduced / runtime | binding MB | reduced rows MB |\n",
              info.row_length, map_gauge.dim());
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const int target : sizes) {
    TriangulateOptions to;
    to.max_edge = edge_for_vertex_count(setup.shape, target);
    const TriMesh mesh = triangulate(setup.shape, to);
    const size_t P = mesh.vertices.size();
    std::vector<float> rest;
    for (const cd& v : mesh.vertices) {
      rest.push_back(static_cast<float>(v.real()));
      rest.push_back(static_cast<float>(v.imag()));
    }
    // Runtime: precompute once, then one product per frame.
    hsib_binding* b = nullptr;
    auto t0 = Clock::now();
    if (hsib_bind(seq, rest.data(), P, 0, &b, error, sizeof error) != HSIB_OK) {
      std::fprintf(stderr, "bench_baked: %s\n", error);
      return 1;
    }
    const double bind_ms = us_since(t0) / 1000;
    std::vector<float> out(2 * P);
    uint32_t frame = 0;
    const double runtime_us = time_per_call([&] {
      hsib_evaluate(b, frame, out.data(), 0);
      frame = (frame + 1) % info.frame_count;
    });
    // C++ reference: basis rows C precomputed, f = C φ + conj(C ψ) per frame.
    t0 = Clock::now();
    const BasisRows rows = evaluate_basis(setup.cage, mesh.vertices, kBasisC);
    const double basis_ms = us_since(t0) / 1000;
    size_t k = 0;
    VectorXcd f;
    const double cpp_us = time_per_call([&] {
      f = evaluate_map(rows, L.maps[k]).f;
      k = (k + 1) % L.maps.size();
    });
    // Alternative: rows over the reduced coefficients (Gauge::Map: f exactly).
    const Eigen::MatrixXd M = reduced_evaluation_matrix(map_gauge, rows);  // 2P × dim
    ReducedRows rr;
    rr.dim = map_gauge.dim();
    rr.vertices = P;
    rr.rows.assign(((P + 63) / 64) * 2 * static_cast<size_t>(rr.dim) * 64, 0.0f);
    for (size_t v = 0; v < P; ++v)
      for (int d = 0; d < rr.dim; ++d)
        for (int c = 0; c < 2; ++c)
          rr.rows[(v / 64) * 2 * static_cast<size_t>(rr.dim) * 64 + (2 * static_cast<size_t>(d) + c) * 64 + v % 64] =
              static_cast<float>(M(static_cast<Eigen::Index>(2 * v + c), d));
    std::vector<std::vector<float>> xs;
    for (const HarmonicMap& m : L.maps) {
      const Eigen::VectorXd x = map_gauge.reduce(m).x;
      xs.emplace_back(x.data(), x.data() + x.size());
    }
    std::vector<float> out2(2 * P);
    k = 0;
    const double reduced_us = time_per_call([&] {
      rr.apply(xs[k], out2);
      k = (k + 1) % xs.size();
    });
    std::printf("| %zu | %.1f | %.1f | %.1f | %.1f | %.1f | %.2f | %.2f | %.1f | %.1f |\n", P, bind_ms, basis_ms, runtime_us, cpp_us,
                reduced_us, cpp_us / runtime_us, reduced_us / runtime_us, static_cast<double>(hsib_binding_bytes(b)) / 1e6,
                static_cast<double>(rr.rows.size() * sizeof(float)) / 1e6);
    std::fflush(stdout);
    hsib_unbind(b);
  }
  hsib_close(seq);
  return 0;
}
