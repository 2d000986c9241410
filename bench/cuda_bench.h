// Shared by the CUDA benchmarks (bench_dense, bench_lockstep): the median time of a call
// by CUDA events, and a fixed SPD test matrix.
#pragma once

#include <algorithm>
#include <deque>
#include <functional>
#include <random>
#include <vector>

#include "device.h"

namespace hsi::bench {

// A = B Bᵀ / m + I, B uniform in [−1, 1] (SPD, condition number ~5), fixed seed.
inline std::vector<double> spd_matrix(int m) {
  std::mt19937 rng(static_cast<unsigned>(m));
  std::uniform_real_distribution<double> u(-1, 1);
  const size_t M = static_cast<size_t>(m);
  std::vector<double> B(M * M), A(M * M, 0.0);
  for (double& v : B) v = u(rng);
  for (size_t j = 0; j < M; ++j)
    for (size_t i = j; i < M; ++i) {
      double s = 0;
      for (size_t k = 0; k < M; ++k) s += B[i + k * M] * B[j + k * M];
      A[i + j * M] = A[j + i * M] = s / m + (i == j ? 1.0 : 0.0);
    }
  return A;
}

// Median time in µs of `body` (CUDA events on `stream`), `reset` (if given) run before
// each call outside the events; three untimed calls first.
inline double median_us(cudaStream_t stream, int reps, const std::function<void()>& reset, const std::function<void()>& body) {
  for (int w = 0; w < 3; ++w) {
    if (reset) reset();
    body();
  }
  std::deque<cuda::Event> starts, stops;
  for (int r = 0; r < reps; ++r) {
    starts.emplace_back(true);
    stops.emplace_back(true);
  }
  for (int r = 0; r < reps; ++r) {
    if (reset) reset();
    HSI_CUDA_CHECK(cudaEventRecord(starts[static_cast<size_t>(r)], stream));
    body();
    HSI_CUDA_CHECK(cudaEventRecord(stops[static_cast<size_t>(r)], stream));
  }
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
  std::vector<double> us;
  for (int r = 0; r < reps; ++r) {
    float ms = 0;
    HSI_CUDA_CHECK(cudaEventElapsedTime(&ms, starts[static_cast<size_t>(r)], stops[static_cast<size_t>(r)]));
    us.push_back(1e3 * ms);
  }
  std::nth_element(us.begin(), us.begin() + reps / 2, us.end());
  return us[static_cast<size_t>(reps / 2)];
}

}  // namespace hsi::bench
