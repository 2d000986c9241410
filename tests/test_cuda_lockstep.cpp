// The lockstep batch's per-sample kernels (newton_kernels.h, issue #23): several Newton
// systems of one setup (the same D, D_H and subset H, each its own targets, point and
// direction) in one launch per call. Each system's results must be bit for bit what the
// one-system call gives on that system's arrays, whatever the other systems hold (one
// of them with a folded sample, so an infinite energy and a zero gradient sit beside
// finite ones), and again on a second launch (the per-system counters left at 0).
// Tests that need a GPU skip with a warning where there is none.
#include <catch2/catch.hpp>

#include <complex>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <cuda_runtime.h>

#include "device.h"
#include "cuda_test.h"
#include "hsi/cuda/newton_core.h"
#include "newton_kernels.h"

namespace hc = hsi::cuda;
namespace hk = hsi::cuda::kernels;

namespace {

template <class T>
hc::DeviceArray<T> upload(const std::vector<T>& v) {
  hc::DeviceArray<T> d(v.size());
  REQUIRE(cudaMemcpy(d.get(), v.data(), d.bytes(), cudaMemcpyHostToDevice) == cudaSuccess);
  return d;
}

template <class T>
std::vector<T> download(const T* d, size_t count) {
  std::vector<T> v(count);
  REQUIRE(cudaMemcpy(v.data(), d, count * sizeof(T), cudaMemcpyDeviceToHost) == cudaSuccess);
  return v;
}

// Bitwise equality of two arrays of doubles (or double2), NaN-safe.
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

}  // namespace

TEST_CASE("lockstep kernels: each system of a batch gets the one-system call's bits", "[cuda][lockstep][small]") {
  HSI_REQUIRE_GPU();
  constexpr int S = 5, G = 5003, h = 911, n = 13, count = 3;
  const size_t g3 = 3 * size_t{G}, g2 = 2 * size_t{G};
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1, 1);

  // Targets near the identity metric (positive definite), points a ≈ 1, |b| < |a| (not
  // folded) except one sample of system 2, small directions, steps in [0, 1].
  std::vector<double> g(S * g3), steps(S * size_t{count});
  std::vector<double2> ab(S * g2), dab(S * g2), D(size_t{G} * n);
  std::vector<int> H(h);
  for (int s = 0; s < S; ++s)
    for (int i = 0; i < G; ++i) {
      double* gi = &g[s * g3 + 3 * size_t(i)];
      gi[0] = 1 + 0.2 * u(rng);
      gi[1] = 0.1 * u(rng);
      gi[2] = 1 + 0.2 * u(rng);
      ab[s * g2 + size_t(i)] = make_double2(1 + 0.3 * u(rng), 0.3 * u(rng));
      ab[s * g2 + G + size_t(i)] = make_double2(0.2 * u(rng), 0.2 * u(rng));
      dab[s * g2 + size_t(i)] = make_double2(0.2 * u(rng), 0.2 * u(rng));
      dab[s * g2 + G + size_t(i)] = make_double2(0.2 * u(rng), 0.2 * u(rng));
    }
  ab[2 * g2 + G + 17] = make_double2(3, 0);  // system 2, sample 17: |b| > |a|, folded
  for (double& v : steps) v = 0.5 * (1 + u(rng));
  for (double2& v : D) v = make_double2(u(rng), u(rng));
  for (int k = 0; k < h; ++k) H[size_t(k)] = (k * 5 + 3) % G;  // distinct (G prime to 5)

  auto dg = upload(g), dsteps = upload(steps);
  auto dab_ = upload(ab), ddab = upload(dab), dD = upload(D);
  auto dH = upload(H);
  hc::DeviceArray<double2> DH(size_t{h} * n);
  REQUIRE(hk::gather_rows(G, h, n, dD.get(), dH.get(), DH.get(), nullptr) == cudaSuccess);

  const size_t parts = hk::reduction_blocks(G);
  hc::DeviceArray<double> part_sum(S * count * parts), part_min(S * parts), energies(S * size_t{count}), safe(S);
  hc::DeviceArray<int> part_bad(S * count * parts);
  hc::DeviceArray<unsigned> done(S);
  REQUIRE(cudaMemset(done.get(), 0, done.bytes()) == cudaSuccess);
  hc::DeviceArray<double2> gab(S * g2), W(S * 6 * size_t{h}), Wt(S * size_t{h} * 6 * n), R(S * 6 * size_t{n} * n);
  hc::DeviceArray<double> Hv(S * 16 * size_t{n} * n);
  // The one-system calls' outputs, one system at a time.
  hc::DeviceArray<double> one_sum(count * parts), one_min(parts), one_e(count), one_safe(1), one_Hv(16 * size_t{n} * n);
  hc::DeviceArray<int> one_bad(count * parts);
  hc::DeviceArray<unsigned> one_done(1);
  REQUIRE(cudaMemset(one_done.get(), 0, one_done.bytes()) == cudaSuccess);
  hc::DeviceArray<double2> one_gab(g2), one_W(6 * size_t{h}), one_Wt(size_t{h} * 6 * n);

  // R = D_Hᴴ Wt would be a ZGEMM; the kernels only need some R per system: made from Wt's
  // first columns so that it differs between systems.
  auto fill_R = [&](const double2* wt, double2* r) {
    REQUIRE(cudaMemcpy(r, wt, 6 * size_t{n} * n * sizeof(double2), cudaMemcpyDeviceToDevice) == cudaSuccess);
  };

  for (const auto projection : {hsi::cuda::sample::Projection::Delete, hsi::cuda::sample::Projection::PartProj}) {
    for (const bool exact : {false, true}) {
      INFO("projection " << static_cast<int>(projection) << ", exact " << exact);
      for (int launch = 0; launch < 2; ++launch) {  // a second launch: the counters were left at 0
        REQUIRE(hk::mean_energies_batched(S, G, dg.get(), dab_.get(), ddab.get(), dsteps.get(), count, part_sum.get(), part_bad.get(),
                                          done.get(), energies.get(), nullptr) == cudaSuccess);
        REQUIRE(hk::gradient_samples_batched(S, G, dg.get(), dab_.get(), gab.get(), nullptr) == cudaSuccess);
        REQUIRE(hk::weighted_rows_batched(S, G, h, n, dH.get(), dg.get(), dab_.get(), projection, exact, DH.get(), W.get(), Wt.get(),
                                          nullptr) == cudaSuccess);
        for (int s = 0; s < S; ++s) fill_R(Wt.get() + s * size_t{h} * 6 * n, R.get() + s * 6 * size_t{n} * n);
        REQUIRE(hk::real_hessian_batched(S, n, R.get(), 7.0, Hv.get(), nullptr) == cudaSuccess);
        REQUIRE(hk::max_safe_step_batched(S, G, dab_.get(), ddab.get(), part_min.get(), done.get(), safe.get(), nullptr) == cudaSuccess);
        REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
        const auto e_all = download(energies.get(), S * size_t{count});
        const auto safe_all = download(safe.get(), S);
        CHECK(download(done.get(), S) == std::vector<unsigned>(S, 0u));

        for (int s = 0; s < S; ++s) {
          INFO("system " << s << ", launch " << launch);
          const double* gs = dg.get() + s * g3;
          const double2* abs = dab_.get() + s * g2;
          const double2* dabs = ddab.get() + s * g2;
          REQUIRE(hk::mean_energies(G, gs, abs, dabs, dsteps.get() + s * count, count, one_sum.get(), one_bad.get(), one_done.get(),
                                    one_e.get(), nullptr) == cudaSuccess);
          REQUIRE(hk::gradient_samples(G, gs, abs, one_gab.get(), nullptr) == cudaSuccess);
          REQUIRE(hk::weighted_rows(G, h, n, dH.get(), gs, abs, projection, exact, DH.get(), one_W.get(), one_Wt.get(), nullptr) ==
                  cudaSuccess);
          REQUIRE(hk::real_hessian(n, R.get() + s * 6 * size_t{n} * n, 7.0, one_Hv.get(), nullptr) == cudaSuccess);
          REQUIRE(hk::max_safe_step(G, abs, dabs, one_min.get(), one_done.get(), one_safe.get(), nullptr) == cudaSuccess);
          REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
          const auto e_one = download(one_e.get(), count);
          CHECK(same_bits(e_one, std::vector<double>(e_all.begin() + s * count, e_all.begin() + (s + 1) * count)));
          CHECK(same_bits(download(one_gab.get(), g2), download(gab.get() + s * g2, g2)));
          CHECK(same_bits(download(one_W.get(), 6 * size_t{h}), download(W.get() + s * 6 * size_t{h}, 6 * size_t{h})));
          CHECK(same_bits(download(one_Wt.get(), size_t{h} * 6 * n), download(Wt.get() + s * size_t{h} * 6 * n, size_t{h} * 6 * n)));
          CHECK(same_bits(download(one_Hv.get(), 16 * size_t{n} * n), download(Hv.get() + s * 16 * size_t{n} * n, 16 * size_t{n} * n)));
          CHECK(same_bits(download(one_safe.get(), 1), std::vector<double>{safe_all[size_t(s)]}));
          // The folded sample: system 2's energies are +inf at every step, the others finite.
          for (int k = 0; k < count; ++k) CHECK(std::isinf(e_one[size_t(k)]) == (s == 2));
        }
        // System 2's gradient is zero at its folded sample (as on the CPU), the others' not.
        const auto gab2 = download(gab.get() + 2 * g2, g2);
        CHECK(gab2[17].x == 0);
        CHECK(gab2[G + 17].x == 0);
      }
    }
  }

  // Bad batch sizes are refused before any launch.
  CHECK(hk::mean_energies_batched(0, G, dg.get(), dab_.get(), ddab.get(), dsteps.get(), count, part_sum.get(), part_bad.get(),
                                  done.get(), energies.get(), nullptr) == cudaErrorInvalidValue);
  CHECK(hk::gradient_samples_batched(hk::kMaxBatchSystems + 1, G, dg.get(), dab_.get(), gab.get(), nullptr) == cudaErrorInvalidValue);
  CHECK(hk::max_safe_step_batched(-1, G, dab_.get(), ddab.get(), part_min.get(), done.get(), safe.get(), nullptr) ==
        cudaErrorInvalidValue);
}
