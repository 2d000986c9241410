// Benchmark of the Newton system's dense Cholesky on the GPU (issue #23): our factor
// and solve (cuda/src/dense_cholesky.h) against cuSOLVER's potrf and potrs, at each
// given scene's system order (m = the metric space's dim + 1, as the CUDA core sets it)
// and at chosen orders. CUDA events around each call, median over the timed calls after
// warm-up (A and b restored outside the timed region), alone and captured into a CUDA
// graph (factor + solve per replay), and the largest relative difference of the two
// solutions. Prints a Markdown table. Not a test: timings only.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cusolverDn.h>
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "cuda_bench.h"
#include "dense_cholesky.h"
#include "device.h"
#include "hsi/cage.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/shape_setup.h"

using namespace hsi;
namespace hc = hsi::cuda;
namespace hk = hsi::cuda::kernels;
using hsi::bench::median_us;
using hsi::bench::spd_matrix;

namespace {

// `body` captured into a graph and instantiated; null where the capture failed.
cudaGraphExec_t capture(cudaStream_t stream, const std::function<void()>& body) {
  cudaGraph_t graph = nullptr;
  HSI_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
  try {
    body();
  } catch (const hc::Error& e) {
    std::fprintf(stderr, "  capture failed: %s\n", e.what());
  }
  const cudaError_t end = cudaStreamEndCapture(stream, &graph);
  if (end != cudaSuccess || !graph) {
    (void)cudaGetLastError();
    return nullptr;
  }
  cudaGraphExec_t exec = nullptr;
  const cudaError_t inst = cudaGraphInstantiate(&exec, graph, 0);
  cudaGraphDestroy(graph);
  if (inst != cudaSuccess) {
    (void)cudaGetLastError();
    return nullptr;
  }
  return exec;
}

struct Row {
  double potrf = 0, factor = 0, potrs = 0, solve = 0, cusolver_graph = -1, ours_graph = -1, max_rel_diff = 0;
  double xpotrf = 0, xpotrs = 0, potrf_batched = 0, potrs_batched = 0;  // cuSOLVER's other entry points
  double factor_solve = 0;  // ours, fused (cholesky_factor_solve)
  int cusolver_info = -1, ours_info = -1;
};

Row time_order(int m, int reps) {
  Row row;
  hc::Stream stream;
  hc::SolverHandle solver(stream);
  const size_t M = static_cast<size_t>(m);
  const std::vector<double> A_host = spd_matrix(m);
  std::vector<double> b_host(M);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double& v : b_host) v = u(rng);
  hc::DeviceArray<double> A0(M * M), b0(M), A(M * M), b(M);
  hc::DeviceArray<int> info(1);
  HSI_CUDA_CHECK(cudaMemcpy(A0.get(), A_host.data(), A0.bytes(), cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaMemcpy(b0.get(), b_host.data(), b0.bytes(), cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaDeviceSynchronize());  // the legacy stream's copies landed before `stream` reads them
  int lwork = 0;
  HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(solver, CUBLAS_FILL_MODE_LOWER, m, A.get(), m, &lwork));
  hc::DeviceArray<double> work(static_cast<size_t>(std::max(lwork, 1)));

  const auto restore_A = [&] { HSI_CUDA_CHECK(cudaMemcpyAsync(A.get(), A0.get(), A.bytes(), cudaMemcpyDeviceToDevice, stream)); };
  const auto restore_b = [&] { HSI_CUDA_CHECK(cudaMemcpyAsync(b.get(), b0.get(), b.bytes(), cudaMemcpyDeviceToDevice, stream)); };
  const auto restore = [&] {
    restore_A();
    restore_b();
  };
  const auto potrf = [&] {
    HSI_CUDA_CHECK(cusolverDnDpotrf(solver, CUBLAS_FILL_MODE_LOWER, m, A.get(), m, work.get(), lwork, info.get()));
  };
  const auto potrs = [&] { HSI_CUDA_CHECK(cusolverDnDpotrs(solver, CUBLAS_FILL_MODE_LOWER, m, 1, A.get(), m, b.get(), m, info.get())); };
  // The 64-bit API (default parameters) and the batched API at batch 1.
  cusolverDnParams_t params = nullptr;
  HSI_CUDA_CHECK(cusolverDnCreateParams(&params));
  size_t x_device_bytes = 0, x_host_bytes = 0;
  HSI_CUDA_CHECK(cusolverDnXpotrf_bufferSize(solver, params, CUBLAS_FILL_MODE_LOWER, m, CUDA_R_64F, A.get(), m, CUDA_R_64F,
                                             &x_device_bytes, &x_host_bytes));
  hc::DeviceArray<unsigned char> x_work(std::max<size_t>(x_device_bytes, 1));
  std::vector<unsigned char> x_host_work(std::max<size_t>(x_host_bytes, 1));
  const auto xpotrf = [&] {
    HSI_CUDA_CHECK(cusolverDnXpotrf(solver, params, CUBLAS_FILL_MODE_LOWER, m, CUDA_R_64F, A.get(), m, CUDA_R_64F, x_work.get(),
                                    x_device_bytes, x_host_work.data(), x_host_bytes, info.get()));
  };
  const auto xpotrs = [&] {
    HSI_CUDA_CHECK(cusolverDnXpotrs(solver, params, CUBLAS_FILL_MODE_LOWER, m, 1, CUDA_R_64F, A.get(), m, CUDA_R_64F, b.get(), m,
                                    info.get()));
  };
  hc::DeviceArray<double*> A_array(1), b_array(1);
  double* const A_ptr = A.get();
  double* const b_ptr = b.get();
  HSI_CUDA_CHECK(cudaMemcpy(A_array.get(), &A_ptr, sizeof A_ptr, cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaMemcpy(b_array.get(), &b_ptr, sizeof b_ptr, cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaDeviceSynchronize());
  const auto potrf_batched = [&] {
    HSI_CUDA_CHECK(cusolverDnDpotrfBatched(solver, CUBLAS_FILL_MODE_LOWER, m, A_array.get(), m, info.get(), 1));
  };
  const auto potrs_batched = [&] {
    HSI_CUDA_CHECK(cusolverDnDpotrsBatched(solver, CUBLAS_FILL_MODE_LOWER, m, 1, A_array.get(), m, b_array.get(), m, info.get(), 1));
  };
  const auto factor = [&] { HSI_CUDA_CHECK(hk::cholesky_factor(m, A.get(), m, info.get(), stream)); };
  const auto solve = [&] { HSI_CUDA_CHECK(hk::cholesky_solve(m, A.get(), m, b.get(), stream)); };
  const auto read_back = [&](std::vector<double>& x, int& inf) {
    x.resize(M);
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    HSI_CUDA_CHECK(cudaMemcpy(x.data(), b.get(), b.bytes(), cudaMemcpyDeviceToHost));
    HSI_CUDA_CHECK(cudaMemcpy(&inf, info.get(), sizeof(int), cudaMemcpyDeviceToHost));
  };

  // cuSOLVER: factor (A restored before each call), then solve on the factor (b restored).
  row.potrf = median_us(stream, reps, restore_A, potrf);
  row.potrs = median_us(stream, reps, restore_b, potrs);
  row.xpotrf = median_us(stream, reps, restore_A, xpotrf);
  row.xpotrs = median_us(stream, reps, restore_b, xpotrs);
  row.potrf_batched = median_us(stream, reps, restore_A, potrf_batched);
  row.potrs_batched = median_us(stream, reps, restore_b, potrs_batched);
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
  HSI_CUDA_CHECK(cusolverDnDestroyParams(params));
  std::vector<double> x_cusolver, x_ours;
  restore();
  potrf();
  potrs();
  read_back(x_cusolver, row.cusolver_info);
  // Ours, the same way.
  row.factor = median_us(stream, reps, restore_A, factor);
  row.solve = median_us(stream, reps, restore_b, solve);
  row.factor_solve = median_us(stream, reps, restore, [&] {
    HSI_CUDA_CHECK(hk::cholesky_factor_solve(m, A.get(), m, b.get(), info.get(), stream));
  });
  restore();
  factor();
  solve();
  read_back(x_ours, row.ours_info);
  double diff = 0, scale = 0;
  for (size_t i = 0; i < M; ++i) {
    diff = std::max(diff, std::abs(x_ours[i] - x_cusolver[i]));
    scale = std::max(scale, std::abs(x_cusolver[i]));
  }
  row.max_rel_diff = diff / std::max(scale, 1e-300);

  // Factor + solve as one graph replay each (A and b restored outside the timed replay).
  const auto factor_solve_cusolver = [&] {
    potrf();
    potrs();
  };
  const auto factor_solve_ours = [&] {
    factor();
    solve();
  };
  for (auto [body, out] : {std::pair{std::function<void()>(factor_solve_cusolver), &row.cusolver_graph},
                           std::pair{std::function<void()>(factor_solve_ours), &row.ours_graph}}) {
    cudaGraphExec_t exec = capture(stream, body);
    if (!exec) continue;
    *out = median_us(stream, reps, restore, [&] { HSI_CUDA_CHECK(cudaGraphLaunch(exec, stream)); });
    cudaGraphExecDestroy(exec);
  }
  return row;
}

// Many systems of one order at once (issue #23: a lockstep batch of sequences needs one
// factor and solve per sequence and step): `batch` copies of the order's matrix, each
// factored and solved. Totals in µs for the whole batch, median over the timed calls.
struct BatchRow {
  double potrf_each = 0, potrf_batched = 0, ours_each = 0, ours_batched = 0;  // factor
  double potrs_each = 0, potrs_batched = 0, solve_each = 0, solve_batched = 0;  // solve on the factor
  double max_rel_diff = 0;  // ours batched against cuSOLVER's potrf + potrs, over the batch
  int bad_info = 0;         // matrices whose info was not 0 (either path)
  bool one_launch = false;
};

BatchRow time_batch(int m, int batch, int reps) {
  BatchRow row;
  hc::Stream stream;
  hc::SolverHandle solver(stream);
  const size_t M = static_cast<size_t>(m), B = static_cast<size_t>(batch);
  const std::vector<double> A_host = spd_matrix(m);
  std::vector<double> A_all(M * M * B), b_all(M * B);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (size_t k = 0; k < B; ++k) std::copy(A_host.begin(), A_host.end(), A_all.begin() + static_cast<std::ptrdiff_t>(k * M * M));
  for (double& v : b_all) v = u(rng);
  hc::DeviceArray<double> A0(M * M * B), b0(M * B), A(M * M * B), b(M * B);
  hc::DeviceArray<int> info(B);
  HSI_CUDA_CHECK(cudaMemcpy(A0.get(), A_all.data(), A0.bytes(), cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaMemcpy(b0.get(), b_all.data(), b0.bytes(), cudaMemcpyHostToDevice));
  std::vector<double*> A_ptrs(B), b_ptrs(B);
  for (size_t k = 0; k < B; ++k) {
    A_ptrs[k] = A.get() + k * M * M;
    b_ptrs[k] = b.get() + k * M;
  }
  hc::DeviceArray<double*> A_array(B), b_array(B);
  HSI_CUDA_CHECK(cudaMemcpy(A_array.get(), A_ptrs.data(), A_array.bytes(), cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaMemcpy(b_array.get(), b_ptrs.data(), b_array.bytes(), cudaMemcpyHostToDevice));
  HSI_CUDA_CHECK(cudaDeviceSynchronize());
  int lwork = 0;
  HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(solver, CUBLAS_FILL_MODE_LOWER, m, A.get(), m, &lwork));
  hc::DeviceArray<double> work(static_cast<size_t>(std::max(lwork, 1)));
  const long long stride = static_cast<long long>(M * M);
  const auto restore_A = [&] { HSI_CUDA_CHECK(cudaMemcpyAsync(A.get(), A0.get(), A.bytes(), cudaMemcpyDeviceToDevice, stream)); };
  const auto restore_b = [&] { HSI_CUDA_CHECK(cudaMemcpyAsync(b.get(), b0.get(), b.bytes(), cudaMemcpyDeviceToDevice, stream)); };
  const auto potrf_each = [&] {
    for (size_t k = 0; k < B; ++k)
      HSI_CUDA_CHECK(cusolverDnDpotrf(solver, CUBLAS_FILL_MODE_LOWER, m, A_ptrs[k], m, work.get(), lwork, info.get() + k));
  };
  const auto potrs_each = [&] {
    for (size_t k = 0; k < B; ++k)
      HSI_CUDA_CHECK(cusolverDnDpotrs(solver, CUBLAS_FILL_MODE_LOWER, m, 1, A_ptrs[k], m, b_ptrs[k], m, info.get() + k));
  };
  const auto ours_each = [&] {
    for (size_t k = 0; k < B; ++k) HSI_CUDA_CHECK(hk::cholesky_factor(m, A_ptrs[k], m, info.get() + k, stream));
  };
  const auto solve_each = [&] {
    for (size_t k = 0; k < B; ++k) HSI_CUDA_CHECK(hk::cholesky_solve(m, A_ptrs[k], m, b_ptrs[k], stream));
  };
  const auto ours_batched = [&] { HSI_CUDA_CHECK(hk::cholesky_factor_batched(m, A.get(), m, stride, info.get(), batch, stream)); };
  const auto solve_batched = [&] {
    HSI_CUDA_CHECK(hk::cholesky_solve_batched(m, A.get(), m, stride, b.get(), m, batch, stream));
  };
  const auto infos_bad = [&] {
    std::vector<int> v(B);
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    HSI_CUDA_CHECK(cudaMemcpy(v.data(), info.get(), info.bytes(), cudaMemcpyDeviceToHost));
    return static_cast<int>(std::count_if(v.begin(), v.end(), [](int i) { return i != 0; }));
  };
  const auto solutions = [&] {
    std::vector<double> x(M * B);
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    HSI_CUDA_CHECK(cudaMemcpy(x.data(), b.get(), b.bytes(), cudaMemcpyDeviceToHost));
    return x;
  };
  row.one_launch = hk::cholesky_batched_in_cluster(m);
  row.potrf_each = median_us(stream, reps, restore_A, potrf_each);
  // cusolverDnDpotrfBatched is meant for small matrices; above m = 512 it is not timed (-1).
  row.potrf_batched = m > 512 ? -1.0 : median_us(stream, m <= 64 ? reps : std::max(5, reps / 10), restore_A, [&] {
    HSI_CUDA_CHECK(cusolverDnDpotrfBatched(solver, CUBLAS_FILL_MODE_LOWER, m, A_array.get(), m, info.get(), batch));
  });
  row.ours_each = median_us(stream, reps, restore_A, ours_each);
  row.ours_batched = median_us(stream, reps, restore_A, ours_batched);
  // Solves on a factor (cuSOLVER's for potrs, ours for ours).
  restore_A();
  potrf_each();
  row.bad_info += infos_bad();
  row.potrs_each = median_us(stream, reps, restore_b, potrs_each);
  // cusolverDnDpotrsBatched (one right-hand side per system, its only form) on the same factors.
  row.potrs_batched = m > 512 ? -1.0 : median_us(stream, m <= 64 ? reps : std::max(5, reps / 10), restore_b, [&] {
    HSI_CUDA_CHECK(cusolverDnDpotrsBatched(solver, CUBLAS_FILL_MODE_LOWER, m, 1, A_array.get(), m, b_array.get(), m, info.get(), batch));
  });
  restore_b();
  potrs_each();
  const std::vector<double> x_ref = solutions();
  restore_A();
  ours_batched();
  row.bad_info += infos_bad();
  row.solve_each = median_us(stream, reps, restore_b, solve_each);
  row.solve_batched = median_us(stream, reps, restore_b, solve_batched);
  restore_b();
  solve_batched();
  const std::vector<double> x = solutions();
  double diff = 0, scale = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    diff = std::max(diff, std::abs(x[i] - x_ref[i]));
    scale = std::max(scale, std::abs(x_ref[i]));
  }
  row.max_rel_diff = diff / std::max(scale, 1e-300);
  return row;
}

std::string us_or_na(double us) {
  if (us < 0) return "n/a";
  char s[32];
  std::snprintf(s, sizeof s, "%.1f", us);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi dense Cholesky benchmark: ours against cuSOLVER's potrf/potrs at the Newton system's orders"};
  std::vector<std::string> scenes;
  std::vector<int> orders{64, 128, 256, 305, 512, 1024};
  int reps = 100, batch = 64;
  app.add_option("scenes", scenes, "Scene files: each adds a row at its Newton system's order");
  app.add_option("--orders", orders, "System orders m to time besides the scenes' (comma-separated)")->delimiter(',')->capture_default_str();
  app.add_option("--reps", reps, "Timed calls per measurement (the median is printed; at least 50)")->capture_default_str();
  app.add_option("--batch", batch, "Systems per batch in the batched table (0: no batched table)")->capture_default_str()->check(CLI::Range(0, 65535));
  CLI11_PARSE(app, argc, argv);
  reps = std::max(reps, 50);
  std::vector<std::pair<std::string, int>> rows;
  for (const std::string& path : scenes) {
    Scene scene = load_scene(path);
    if (!scene.cage) scene.cage = build_cage(scene.shape, scene.cage_options);
    const auto setup = make_shape_setup(scene);
    rows.emplace_back(scene.name.empty() ? path : scene.name, setup->metric_space.dim() + 1);
    std::fprintf(stderr, "%s: m = %d\n", rows.back().first.c_str(), rows.back().second);
  }
  for (int m : orders) rows.emplace_back("", m);
  std::string why;
  if (!hc::device_available(&why)) {
    std::fprintf(stderr, "bench_dense: %s\n", why.c_str());
    return 1;
  }

  std::printf("## Dense Cholesky, FP64, one right-hand side: ours (cuda/src/dense_cholesky.h) against cuSOLVER\n\n"
              "Median µs over %d calls (CUDA events, after 3 untimed calls; A and b restored outside the timed "
              "region). graph: factor + solve captured into one CUDA graph, per replay. max rel diff: "
              "max |x_ours − x_cuSOLVER| / max |x_cuSOLVER|. A = B Bᵀ/m + I, random B. Our factor is one "
              "kernel (a cluster of 8 blocks) up to m = %d, ceil(m/32) launches above; the caller prefers cuSOLVER "
              "above m = %d (kCholeskyPreferredMaxOrder). Xpotrf/Xpotrs: cuSOLVER's 64-bit API (default params); "
              "batched: cusolverDnDpotrfBatched/DpotrsBatched at batch 1 (timed, not wired); our factor_solve: "
              "cholesky_factor_solve, factor with the forward substitution fused, then back substitution (A and b restored). "
              "Our solve: cholesky_solve, one kernel, a cluster of 8 blocks holding L up to m = %d (what the CUDA core "
              "uses after potrf and with a kept factor), one block above.\n\n",
              reps, hk::kCholeskyClusterMaxOrder, hk::kCholeskyPreferredMaxOrder, hk::kCholeskySolveClusterMaxOrder);
  std::printf("| scene | m | potrf µs | our factor µs | potrf / ours | potrs µs | our solve µs | potrs / ours | "
              "cuSOLVER graph µs | our graph µs | cuSOLVER / ours (graph) | max rel diff | info (cuSOLVER, ours) | "
              "Xpotrf µs | Xpotrs µs | potrfBatched µs | potrsBatched µs | our factor_solve µs |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, m] : rows) {
    std::fprintf(stderr, "m = %d%s%s\n", m, name.empty() ? "" : ": ", name.c_str());
    const Row r = time_order(m, reps);
    const std::string graph_ratio =
        r.cusolver_graph > 0 && r.ours_graph > 0 ? us_or_na(r.cusolver_graph / r.ours_graph).append("x") : "n/a";
    std::printf("| %s | %d | %.1f | %.1f | %.1fx | %.1f | %.1f | %.1fx | %s | %s | %s | %.1e | %d, %d | %.1f | %.1f | %.1f | %.1f | %.1f |\n",
                name.empty() ? "-" : name.c_str(), m, r.potrf, r.factor, r.potrf / r.factor, r.potrs, r.solve, r.potrs / r.solve,
                us_or_na(r.cusolver_graph).c_str(), us_or_na(r.ours_graph).c_str(), graph_ratio.c_str(), r.max_rel_diff,
                r.cusolver_info, r.ours_info, r.xpotrf, r.xpotrs, r.potrf_batched, r.potrs_batched, r.factor_solve);
    std::fflush(stdout);
  }
  if (batch > 0) {
    std::printf("\n## %d systems of one order at once (a lockstep batch's factor and solve per step)\n\n"
                "Totals for the whole batch in µs, median over the timed calls (A or b restored outside the timed region), "
                "and per system. each: one call per system on one stream; potrfBatched: cusolverDnDpotrfBatched at batch "
                "%d (%s, not above m = 512); ours batched: cholesky_factor_batched / cholesky_solve_batched (one launch of %d clusters where "
                "the order fits the cluster kernel, else one call per system). max rel diff: ours batched (factor and "
                "solve) against potrf + potrs, over the batch. potrsBatched: cusolverDnDpotrsBatched on potrf's factors.\n\n",
                batch, batch, "fewer timed calls above m = 64", batch);
    std::printf("| scene | m | potrf each µs | potrfBatched µs | our factor each µs | our factor batched µs | per system µs | "
                "potrf each / ours batched | potrfBatched / ours batched | potrs each µs | potrsBatched µs | our solve each µs | "
                "our solve batched µs | per system µs | one launch | info ≠ 0 | max rel diff |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& [name, m] : rows) {
      std::fprintf(stderr, "batch of %d at m = %d%s%s\n", batch, m, name.empty() ? "" : ": ", name.c_str());
      const BatchRow r = time_batch(m, batch, reps);
      char vs_batched[32] = "n/a";
      if (r.potrf_batched > 0) std::snprintf(vs_batched, sizeof vs_batched, "%.2fx", r.potrf_batched / r.ours_batched);
      std::printf("| %s | %d | %.1f | %s | %.1f | %.1f | %.2f | %.1fx | %s | %.1f | %s | %.1f | %.1f | %.2f | %s | %d | %.1e |\n",
                  name.empty() ? "-" : name.c_str(), m, r.potrf_each, us_or_na(r.potrf_batched).c_str(), r.ours_each, r.ours_batched,
                  r.ours_batched / batch, r.potrf_each / r.ours_batched, vs_batched, r.potrs_each,
                  us_or_na(r.potrs_batched).c_str(), r.solve_each, r.solve_batched,
                  r.solve_batched / batch, r.one_launch ? "yes" : "no", r.bad_info, r.max_rel_diff);
      std::fflush(stdout);
    }
  }
  return 0;
}
