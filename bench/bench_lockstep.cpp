// What a lockstep batch would cost the GPU (issue #23): the device work of a warm frame's
// Newton stages for S systems of one setup (the same D, D_H, subset H, reduced space; each
// system its own targets, point and factor), done
//   each     as today's stepper does it: one system's kernels after another on one stream;
//   k str.   the same one-system calls spread over k streams (system j on stream j mod k),
//            as bench_batch's workers share the GPU, without their host side;
//   lockstep each stage once for all S systems: the products with D as one ZGEMM over the
//            systems' 2S columns, the per-sample kernels over a grid of samples × systems
//            (newton_kernels.h's *_batched, each system's bits the one-system call's), the
//            Hessians' products and the reduced systems as strided-batched GEMMs sharing
//            D_H and T, the factors by cuSOLVER's potrfBatched, the solves by
//            cholesky_solve_batched.
// Stages (one call each per system and frame, cumulatively a warm frame's least device
// work, as bench_stages counts it): start (x → coefficients → a, b at G and E), gradient
// (per-sample ∂E, Dᴴ, the reduced gradient), chord (the kept factor's solve, the direction
// at G: coefficients and D d), try (the safe step and one trial energy), exact H / exact G
// (weights, weighted rows, the Hessian's product, the real Hessian, the reduced system
// Tᵀ H T), factor (Cholesky and the triangular solves), certificate (the full coefficients
// and DeviceCertifier's launches, one map or S at once). Not here: the ridge and the
// scalars between stages (one-block kernels), the host.
// Points are blends of the scene's first two keyframes (one per system), targets near
// the identity metric, the factored matrices a fixed SPD one: the costs, not a solve.
// µs per system: CUDA events around the stage for all S systems, median of the timed
// repetitions after warm-up, divided by S. Prints Markdown tables. Not a test.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cublas_v2.h>
#include <cusolverDn.h>
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "bench_scenes.h"
#include "cuda_bench.h"
#include "dense_cholesky.h"
#include "device_certifier.h"
#include "device.h"
#include "hsi/cuda/clocks.h"
#include "hsi/cuda/newton_core.h"
#include "newton_kernels.h"

using namespace hsi;
namespace hc = hsi::cuda;
namespace hk = hsi::cuda::kernels;
using hsi::bench::median_us;
using hsi::bench::spd_matrix;

namespace {

const cuDoubleComplex kOne{1, 0}, kZero{0, 0};
const double kOneD = 1, kZeroD = 0;

enum Stage { kStart, kGradient, kChord, kTry, kCertify, kExactH, kExactG, kFactor, kRowsH, kRowsG, kProdH, kProd3mH, kProdTH, kReduced, kStages };
const char* const kStageNames[kStages] = {"start (x → a, b at G, E)", "gradient (∂E at G, Dᴴ, Tᵀ)", "chord (kept factor's solve, d at G)",
                                          "try (safe step, one trial energy)",
                                          "certificate (x → full coefficients, the certificate)", "exact system over H", "exact system over G",
                                          "factor + triangular solves", "(of exact over H: the weights and weighted rows alone)",
                                          "(of exact over G: the weights and weighted rows alone)",
                                          "(of exact over H: the Hessians' product D_Hᴴ Wt alone)",
                                          "(the same product by ZGEMM3m, Gauss's three real products)",
                                          "(the same product transposed: Wtᴴ D_H)",
                                          "(of exact: the reduced system Tᵀ H T alone, two GEMMs)"};

// One scene's device data for up to S systems, and the stages' three ways.
struct Bench {
  int G = 0, n = 0, h = 0, m = 0, S = 0, streams = 1;
  bool tall = false;  // lockstep's products with D by tall_times_two_batched (each system's bits) instead of one ZGEMM
  bool strided = false;  // lockstep's Hessian products as a strided-batched ZGEMM instead of one ZGEMM over every system's rows
  hc::Stream main;
  std::vector<std::unique_ptr<hc::Stream>> side;
  std::vector<std::unique_ptr<hc::BlasHandle>> blas;      // one per side stream; blas[0] also lockstep's (on main)
  std::vector<std::unique_ptr<hc::SolverHandle>> solver;  // likewise
  std::unique_ptr<hc::BlasHandle> main_blas;
  std::unique_ptr<hc::SolverHandle> main_solver;
  std::deque<hc::Event> fork, join;
  hc::DeviceArray<double2> D, DH, AB, dAB, GAB, C, dC, W, Wt, Wall, Wtall, R;
  hc::DeviceArray<int> H, all;
  hc::DeviceArray<double> g, Tc, x, d, gr, Hv, Y, Hr, L, A0, rhs, steps, zeros, energies, safe, part_sum, part_min, work;
  hc::DeviceArray<int> part_bad, info;
  hc::DeviceArray<unsigned> done;
  hc::DeviceArray<double*> A_array;
  hc::DeviceArray<double> X, full;   // x → the full coefficients (4M × m; its cost), and the maps' [φ | ψ] (2M complex each)
  hc::DeviceArray<double2> maps;
  std::unique_ptr<hc::DeviceCertifier> main_cert, batch_cert;  // one map at a time on main; S maps at once on main
  std::vector<std::unique_ptr<hc::DeviceCertifier>> side_cert;  // one per side stream
  int M = 0;
  int lwork = 0;

  Bench(const ShapeSetup& setup, const std::vector<HarmonicMap>& keys, int systems, int stream_count, bool tall_products,
        bool strided_hessian)
      : S(systems), streams(stream_count), tall(tall_products), strided(strided_hessian) {
    const MapSpace& space = setup.metric_space;
    G = static_cast<int>(setup.D_G.rows());
    n = static_cast<int>(setup.D_G.cols());
    h = static_cast<int>(setup.H.size());
    m = space.dim() + 1;
    const size_t Gz = size_t(G), nz = size_t(n), hz = size_t(h), mz = size_t(m), Sz = size_t(S);
    for (int k = 0; k < streams; ++k) {
      side.push_back(std::make_unique<hc::Stream>());
      blas.push_back(std::make_unique<hc::BlasHandle>(*side.back()));
      solver.push_back(std::make_unique<hc::SolverHandle>(*side.back()));
      fork.emplace_back(false);
      join.emplace_back(false);
    }
    main_blas = std::make_unique<hc::BlasHandle>(main);
    main_solver = std::make_unique<hc::SolverHandle>(main);
    auto up = [&](auto& dst, const auto& src) {
      using T = typename std::decay_t<decltype(src)>::value_type;
      dst = std::decay_t<decltype(dst)>(src.size());
      HSI_CUDA_CHECK(cudaMemcpy(dst.get(), src.data(), src.size() * sizeof(T), cudaMemcpyHostToDevice));
    };
    // D at G, its rows at H, the indices of H and of all of G.
    std::vector<double2> Dh(Gz * nz);
    std::memcpy(Dh.data(), setup.D_G.data(), Dh.size() * sizeof(double2));
    up(D, Dh);
    up(H, setup.H);
    std::vector<int> iota(Gz);
    for (size_t i = 0; i < Gz; ++i) iota[i] = static_cast<int>(i);
    up(all, iota);
    DH = hc::DeviceArray<double2>(hz * nz);
    HSI_CUDA_CHECK(hk::gather_rows(G, h, n, D.get(), H.get(), DH.get(), main));
    // Tc (4n × m, complex order: row 2j Re φ_j, 2j+1 Im φ_j, 2n+2j Re ψ_j, 2n+2j+1 Im ψ_j),
    // its last column the rotation generator at the first keyframe; x per system a blend.
    const Eigen::MatrixXd T = Eigen::MatrixXd(space.T());
    const MapSpace::Canonical k0 = space.reduce(keys.front()), k1 = space.reduce(keys.back());
    const Eigen::VectorXd u = space.rotation_generator(T * k0.x);
    std::vector<double> Tch(4 * nz * mz, 0.0), xh(mz * Sz, 0.0);
    for (int c = 0; c < m; ++c)
      for (int j = 0; j < n; ++j)
        for (int part = 0; part < 4; ++part) {
          const int row = part * n + j;  // v layout
          const int crow = (part / 2) * 2 * n + 2 * j + part % 2;
          Tch[size_t(c) * 4 * nz + size_t(crow)] = c < m - 1 ? T(row, c) : u(row);
        }
    up(Tc, Tch);
    for (int s = 0; s < S; ++s) {
      const double t = S == 1 ? 0.5 : static_cast<double>(s) / (S - 1);
      const Eigen::VectorXd xs = (1 - t) * k0.x + t * k1.x;
      for (int c = 0; c < m - 1; ++c) xh[size_t(s) * mz + size_t(c)] = xs(c);
    }
    up(x, xh);
    // Targets near the identity metric, a small direction in x.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> un(-1, 1);
    std::vector<double> gh(3 * Gz * Sz), dh(mz * Sz);
    for (size_t i = 0; i < Gz * Sz; ++i) {
      gh[3 * i] = 1 + 0.05 * un(rng);
      gh[3 * i + 1] = 0.02 * un(rng);
      gh[3 * i + 2] = 1 + 0.05 * un(rng);
    }
    for (double& v : dh) v = 1e-3 * un(rng);
    up(g, gh);
    up(d, dh);
    const std::vector<double> A = spd_matrix(m);
    std::vector<double> Ah(mz * mz * Sz);
    for (size_t s = 0; s < Sz; ++s) std::copy(A.begin(), A.end(), Ah.begin() + static_cast<std::ptrdiff_t>(s * mz * mz));
    up(A0, Ah);
    L = hc::DeviceArray<double>(mz * mz * Sz);
    HSI_CUDA_CHECK(cudaMemcpy(L.get(), A0.get(), L.bytes(), cudaMemcpyDeviceToDevice));
    HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(*main_solver, CUBLAS_FILL_MODE_LOWER, m, L.get(), m, &lwork));
    {  // the kept factors: one factorisation each
      hc::DeviceArray<double> w0(size_t(std::max(lwork, 1)));
      hc::DeviceArray<int> i0(1);
      for (size_t s = 0; s < Sz; ++s)
        HSI_CUDA_CHECK(cusolverDnDpotrf(*main_solver, CUBLAS_FILL_MODE_LOWER, m, L.get() + s * mz * mz, m, w0.get(), lwork, i0.get()));
    }
    Hr = hc::DeviceArray<double>(mz * mz * Sz);
    work = hc::DeviceArray<double>(size_t(std::max(lwork, 1)) * size_t(streams));
    std::vector<double*> ptrs(Sz);
    for (size_t s = 0; s < Sz; ++s) ptrs[s] = Hr.get() + s * mz * mz;
    up(A_array, ptrs);
    C = hc::DeviceArray<double2>(2 * nz * Sz);
    dC = hc::DeviceArray<double2>(2 * nz * Sz);
    AB = hc::DeviceArray<double2>(2 * Gz * Sz);
    dAB = hc::DeviceArray<double2>(2 * Gz * Sz);
    GAB = hc::DeviceArray<double2>(2 * Gz * Sz);
    W = hc::DeviceArray<double2>(6 * hz * Sz);
    Wt = hc::DeviceArray<double2>(hz * 6 * nz * Sz);
    Wall = hc::DeviceArray<double2>(6 * Gz * Sz);
    Wtall = hc::DeviceArray<double2>(Gz * 6 * nz * Sz);
    R = hc::DeviceArray<double2>(6 * nz * nz * Sz);
    gr = hc::DeviceArray<double>(mz * Sz);
    Hv = hc::DeviceArray<double>(16 * nz * nz * Sz);
    Y = hc::DeviceArray<double>(4 * nz * mz * Sz);
    rhs = hc::DeviceArray<double>(mz * Sz);
    HSI_CUDA_CHECK(cudaMemset(rhs.get(), 0, rhs.bytes()));
    steps = hc::DeviceArray<double>(Sz);
    std::vector<double> half(Sz, 0.5);
    HSI_CUDA_CHECK(cudaMemcpy(steps.get(), half.data(), steps.bytes(), cudaMemcpyHostToDevice));
    zeros = hc::DeviceArray<double>(Sz);
    HSI_CUDA_CHECK(cudaMemset(zeros.get(), 0, zeros.bytes()));
    energies = hc::DeviceArray<double>(Sz);
    safe = hc::DeviceArray<double>(Sz);
    const size_t parts = hk::reduction_blocks(G);
    part_sum = hc::DeviceArray<double>(parts * Sz);
    part_bad = hc::DeviceArray<int>(parts * Sz);
    part_min = hc::DeviceArray<double>(parts * Sz);
    done = hc::DeviceArray<unsigned>(Sz);
    info = hc::DeviceArray<int>(Sz);
    HSI_CUDA_CHECK(cudaMemset(done.get(), 0, done.bytes()));
    HSI_CUDA_CHECK(cudaDeviceSynchronize());
    // The certificate: each system's map (x expanded; its full coefficients on the device)
    // and a certifier for one map per stream, one for S maps.
    M = space.full_size();
    std::vector<double2> mh(2 * size_t(M) * Sz);
    for (int s = 0; s < S; ++s) {
      Eigen::VectorXd xs(m - 1);
      for (int c = 0; c < m - 1; ++c) xs(c) = xh[size_t(s) * mz + size_t(c)];
      const HarmonicMap map = space.expand(xs);
      for (int j = 0; j < M; ++j) {
        mh[size_t(s) * 2 * size_t(M) + size_t(j)] = make_double2(map.phi(j).real(), map.phi(j).imag());
        mh[size_t(s) * 2 * size_t(M) + size_t(M + j)] = make_double2(map.psi(j).real(), map.psi(j).imag());
      }
    }
    up(maps, mh);
    std::vector<double> Xh(4 * size_t(M) * mz);
    for (double& v : Xh) v = un(rng);
    up(X, Xh);
    full = hc::DeviceArray<double>(4 * size_t(M) * Sz);
    main_cert = std::make_unique<hc::DeviceCertifier>(setup, main, *main_blas);
    batch_cert = std::make_unique<hc::DeviceCertifier>(setup, main, *main_blas, S);
    for (int k = 0; k < streams; ++k) side_cert.push_back(std::make_unique<hc::DeviceCertifier>(setup, *side[size_t(k)], *blas[size_t(k)]));
    // Real points: a, b at G from x, the direction at G.
    lockstep(kStart);
    lockstep(kChord);
    HSI_CUDA_CHECK(cudaStreamSynchronize(main));
  }

  // R = D_rowsᴴ [Wt_first … Wt_first+count−1]: the systems' weighted rows lie side by side
  // (rows × 6n each), and so do their R (n × 6n), so one product serves any number of them
  // (with count 1, the stepper's own call).
  void hessian_product(cublasHandle_t b, int rows, const double2* rowsD, const double2* wt, double2* r, int count) const {
    HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n * count, rows, &kOne, rowsD, rows, wt, rows, &kZero, r, n));
  }
  // The reduced systems Tᵀ Hv T of systems [first, first + count): Y = Hv T, then Tᵀ Y;
  // one system by the stepper's two GEMMs, or (lockstep) as strided batches sharing T.
  void reduced_system(cublasHandle_t b, int first, int count, bool lockstep) {
    const size_t nz = size_t(n), mz = size_t(m);
    const double* hv = Hv.get() + size_t(first) * 16 * nz * nz;
    double* y = Y.get() + size_t(first) * 4 * nz * mz;
    double* hr = Hr.get() + size_t(first) * mz * mz;
    if (!lockstep) {
      HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n, m, 4 * n, &kOneD, hv, 4 * n, Tc.get(), 4 * n, &kZeroD, y, 4 * n));
      HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_T, CUBLAS_OP_N, m, m, 4 * n, &kOneD, Tc.get(), 4 * n, y, 4 * n, &kZeroD, hr, m));
      return;
    }
    HSI_CUDA_CHECK(cublasDgemmStridedBatched(b, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n, m, 4 * n, &kOneD, hv, 4 * n,
                                             static_cast<long long>(16 * nz * nz), Tc.get(), 4 * n, 0, &kZeroD, y, 4 * n,
                                             static_cast<long long>(4 * nz * mz), count));
    HSI_CUDA_CHECK(cublasDgemmStridedBatched(b, CUBLAS_OP_T, CUBLAS_OP_N, m, m, 4 * n, &kOneD, Tc.get(), 4 * n, 0, y, 4 * n,
                                             static_cast<long long>(4 * nz * mz), &kZeroD, hr, m, static_cast<long long>(mz * mz), count));
  }

  // System s's pieces.
  double* xs(int s) const { return x.get() + size_t(s) * size_t(m); }
  double2* Cs(int s) const { return C.get() + size_t(s) * 2 * size_t(n); }
  double2* dCs(int s) const { return dC.get() + size_t(s) * 2 * size_t(n); }
  double2* ABs(int s) const { return AB.get() + size_t(s) * 2 * size_t(G); }
  double2* dABs(int s) const { return dAB.get() + size_t(s) * 2 * size_t(G); }
  double2* GABs(int s) const { return GAB.get() + size_t(s) * 2 * size_t(G); }
  double* gs(int s) const { return g.get() + size_t(s) * 3 * size_t(G); }
  size_t parts() const { return hk::reduction_blocks(G); }

  // The one-system calls of a stage for system s on stream st (handles b, so).
  void one(Stage stage, int s, cudaStream_t st, cublasHandle_t b, cusolverDnHandle_t so, double* wk) {
    const size_t mz = size_t(m), nz = size_t(n);
    switch (stage) {
      case kStart:
        HSI_CUDA_CHECK(hk::tall_times_one(4 * n, m, Tc.get(), xs(s), reinterpret_cast<double*>(Cs(s)), st));
        HSI_CUDA_CHECK(hk::tall_times_two(G, n, D.get(), Cs(s), ABs(s), st));
        HSI_CUDA_CHECK(hk::mean_energies(G, gs(s), ABs(s), dABs(s), zeros.get() + s, 1, part_sum.get() + size_t(s) * parts(),
                                         part_bad.get() + size_t(s) * parts(), done.get() + s, energies.get() + s, st));
        break;
      case kGradient: {
        HSI_CUDA_CHECK(hk::gradient_samples(G, gs(s), ABs(s), GABs(s), st));
        hk::ReducedGradient rg;  // the reduced gradient in the same launch's last block, as the stepper does
        rg.T = Tc.get();
        rg.m = m;
        rg.scale = 1.0 / G;
        rg.g = gr.get() + size_t(s) * mz;
        rg.done = done.get() + s;
        HSI_CUDA_CHECK(hk::tall_adjoint_times_two(G, n, D.get(), GABs(s), Cs(s), st, rg));
        break;
      }
      case kChord:
        HSI_CUDA_CHECK(hk::cholesky_solve(m, L.get() + size_t(s) * mz * mz, m, d.get() + size_t(s) * mz, st));
        HSI_CUDA_CHECK(hk::tall_times_one(4 * n, m, Tc.get(), d.get() + size_t(s) * mz, reinterpret_cast<double*>(dCs(s)), st));
        HSI_CUDA_CHECK(hk::tall_times_two(G, n, D.get(), dCs(s), dABs(s), st));
        break;
      case kTry:
        HSI_CUDA_CHECK(hk::max_safe_step(G, ABs(s), dABs(s), part_min.get() + size_t(s) * parts(), done.get() + s, safe.get() + s, st));
        HSI_CUDA_CHECK(hk::mean_energies(G, gs(s), ABs(s), dABs(s), steps.get() + s, 1, part_sum.get() + size_t(s) * parts(),
                                         part_bad.get() + size_t(s) * parts(), done.get() + s, energies.get() + s, st));
        break;
      case kCertify: {
        HSI_CUDA_CHECK(hk::tall_times_one(4 * M, m, X.get(), xs(s), full.get() + size_t(s) * 4 * size_t(M), st));
        hc::DeviceCertifier& c = st == static_cast<cudaStream_t>(main) ? *main_cert : *side_cert[size_t(s % streams)];
        c.enqueue(maps.get() + size_t(s) * 2 * size_t(M), CertificateOptions{});
        break;
      }
      case kRowsH:
      case kRowsG:
      case kExactH:
      case kExactG: {
        const bool all_rows = stage == kExactG || stage == kRowsG;
        const int rows = all_rows ? G : h;
        double2* w = all_rows ? Wall.get() + size_t(s) * 6 * size_t(G) : W.get() + size_t(s) * 6 * size_t(h);
        double2* wt = all_rows ? Wtall.get() + size_t(s) * size_t(G) * 6 * nz : Wt.get() + size_t(s) * size_t(h) * 6 * nz;
        const double2* rowsD = all_rows ? D.get() : DH.get();
        double2* r = R.get() + size_t(s) * 6 * nz * nz;
        HSI_CUDA_CHECK(hk::weighted_rows(G, rows, n, all_rows ? all.get() : H.get(), gs(s), ABs(s), hc::sample::Projection::PartProj, true,
                                         rowsD, w, wt, st));
        if (stage == kRowsH || stage == kRowsG) break;
        hessian_product(b, rows, rowsD, wt, r, 1);
        HSI_CUDA_CHECK(hk::real_hessian(n, r, rows, Hv.get() + size_t(s) * 16 * nz * nz, st));
        reduced_system(b, s, 1, false);
        break;
      }
      case kProdH:
      case kProd3mH:
      case kProdTH: {
        double2* wt = Wt.get() + size_t(s) * size_t(h) * 6 * nz;
        double2* r = R.get() + size_t(s) * 6 * nz * nz;
        if (stage == kProdH)
          hessian_product(b, h, DH.get(), wt, r, 1);
        else if (stage == kProd3mH)
          HSI_CUDA_CHECK(cublasZgemm3m(b, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n, h, &kOne, DH.get(), h, wt, h, &kZero, r, n));
        else
          HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_C, CUBLAS_OP_N, 6 * n, n, h, &kOne, wt, h, DH.get(), h, &kZero, r, 6 * n));
        break;
      }
      case kReduced:
        reduced_system(b, s, 1, false);
        break;
      case kFactor: {
        double* A = Hr.get() + size_t(s) * mz * mz;
        HSI_CUDA_CHECK(cudaMemcpyAsync(A, A0.get() + size_t(s) * mz * mz, mz * mz * sizeof(double), cudaMemcpyDeviceToDevice, st));
        HSI_CUDA_CHECK(cusolverDnDpotrf(so, CUBLAS_FILL_MODE_LOWER, m, A, m, wk, lwork, info.get() + s));
        HSI_CUDA_CHECK(hk::cholesky_solve(m, A, m, rhs.get() + size_t(s) * mz, st));
        break;
      }
      default: break;
    }
  }

  void each(Stage stage) {
    for (int s = 0; s < S; ++s) one(stage, s, main, *main_blas, *main_solver, work.get());
  }

  void spread(Stage stage) {
    HSI_CUDA_CHECK(cudaEventRecord(fork[0], main));
    for (int k = 0; k < streams; ++k) HSI_CUDA_CHECK(cudaStreamWaitEvent(*side[size_t(k)], fork[0], 0));
    for (int s = 0; s < S; ++s) {
      const size_t k = size_t(s % streams);
      one(stage, s, *side[k], *blas[k], *solver[k], work.get() + k * size_t(std::max(lwork, 1)));
    }
    for (int k = 0; k < streams; ++k) {
      HSI_CUDA_CHECK(cudaEventRecord(join[size_t(k)], *side[size_t(k)]));
      HSI_CUDA_CHECK(cudaStreamWaitEvent(main, join[size_t(k)], 0));
    }
  }

  void lockstep(Stage stage) {
    const cudaStream_t st = main;
    cublasHandle_t b = *main_blas;
    const size_t mz = size_t(m), nz = size_t(n);
    switch (stage) {
      case kStart:
        // C (complex order, 4n reals per system) = Tc x for all systems; then [a | b] = D C.
        HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n, S, m, &kOneD, Tc.get(), 4 * n, x.get(), m, &kZeroD,
                                   reinterpret_cast<double*>(C.get()), 4 * n));
        if (tall) HSI_CUDA_CHECK(hk::tall_times_two_batched(S, G, n, D.get(), C.get(), AB.get(), st));
        else HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, G, 2 * S, n, &kOne, D.get(), G, C.get(), n, &kZero, AB.get(), G));
        HSI_CUDA_CHECK(hk::mean_energies_batched(S, G, g.get(), AB.get(), dAB.get(), zeros.get(), 1, part_sum.get(), part_bad.get(),
                                                 done.get(), energies.get(), st));
        break;
      case kGradient:
        HSI_CUDA_CHECK(hk::gradient_samples_batched(S, G, g.get(), AB.get(), GAB.get(), st));
        HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_C, CUBLAS_OP_N, n, 2 * S, G, &kOne, D.get(), G, GAB.get(), G, &kZero, C.get(), n));
        HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_T, CUBLAS_OP_N, m, S, 4 * n, &kOneD, Tc.get(), 4 * n, reinterpret_cast<double*>(C.get()),
                                   4 * n, &kZeroD, gr.get(), m));
        break;
      case kChord:
        HSI_CUDA_CHECK(hk::cholesky_solve_batched(m, L.get(), m, static_cast<long long>(mz * mz), d.get(), m, S, st));
        HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n, S, m, &kOneD, Tc.get(), 4 * n, d.get(), m, &kZeroD,
                                   reinterpret_cast<double*>(dC.get()), 4 * n));
        if (tall) HSI_CUDA_CHECK(hk::tall_times_two_batched(S, G, n, D.get(), dC.get(), dAB.get(), st));
        else HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, G, 2 * S, n, &kOne, D.get(), G, dC.get(), n, &kZero, dAB.get(), G));
        break;
      case kTry:
        HSI_CUDA_CHECK(hk::max_safe_step_batched(S, G, AB.get(), dAB.get(), part_min.get(), done.get(), safe.get(), st));
        HSI_CUDA_CHECK(hk::mean_energies_batched(S, G, g.get(), AB.get(), dAB.get(), steps.get(), 1, part_sum.get(), part_bad.get(),
                                                 done.get(), energies.get(), st));
        break;
      case kCertify:
        HSI_CUDA_CHECK(cublasDgemm(b, CUBLAS_OP_N, CUBLAS_OP_N, 4 * M, S, m, &kOneD, X.get(), 4 * M, x.get(), m, &kZeroD, full.get(),
                                   4 * M));
        batch_cert->enqueue(maps.get(), CertificateOptions{}, S);
        break;
      case kRowsH:
      case kRowsG:
      case kExactH:
      case kExactG: {
        const bool all_rows = stage == kExactG || stage == kRowsG;
        const int rows = all_rows ? G : h;
        double2* w = all_rows ? Wall.get() : W.get();
        double2* wt = all_rows ? Wtall.get() : Wt.get();
        const double2* rowsD = all_rows ? D.get() : DH.get();
        HSI_CUDA_CHECK(hk::weighted_rows_batched(S, G, rows, n, all_rows ? all.get() : H.get(), g.get(), AB.get(),
                                                 hc::sample::Projection::PartProj, true, rowsD, w, wt, st));
        if (stage == kRowsH || stage == kRowsG) break;
        // One product over every system's weighted rows, or the same as a strided batch.
        if (strided)
          HSI_CUDA_CHECK(cublasZgemmStridedBatched(b, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n, rows, &kOne, rowsD, rows, 0, wt, rows,
                                                   static_cast<long long>(size_t(rows) * 6 * nz), &kZero, R.get(), n,
                                                   static_cast<long long>(6 * nz * nz), S));
        else
          hessian_product(b, rows, rowsD, wt, R.get(), S);
        HSI_CUDA_CHECK(hk::real_hessian_batched(S, n, R.get(), rows, Hv.get(), st));
        reduced_system(b, 0, S, true);
        break;
      }
      case kProdH:
        hessian_product(b, h, DH.get(), Wt.get(), R.get(), S);
        break;
      case kProd3mH:
        HSI_CUDA_CHECK(cublasZgemm3m(b, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n * S, h, &kOne, DH.get(), h, Wt.get(), h, &kZero, R.get(), n));
        break;
      case kProdTH:  // [R_1ᴴ; …; R_Sᴴ] (6nS × n)
        HSI_CUDA_CHECK(cublasZgemm(b, CUBLAS_OP_C, CUBLAS_OP_N, 6 * n * S, n, h, &kOne, Wt.get(), h, DH.get(), h, &kZero, R.get(), 6 * n * S));
        break;
      case kReduced:
        reduced_system(b, 0, S, true);
        break;
      case kFactor:
        HSI_CUDA_CHECK(cudaMemcpyAsync(Hr.get(), A0.get(), A0.bytes(), cudaMemcpyDeviceToDevice, st));
        HSI_CUDA_CHECK(cusolverDnDpotrfBatched(*main_solver, CUBLAS_FILL_MODE_LOWER, m, A_array.get(), m, info.get(), S));
        HSI_CUDA_CHECK(hk::cholesky_solve_batched(m, Hr.get(), m, static_cast<long long>(mz * mz), rhs.get(), m, S, st));
        break;
      default: break;
    }
  }

  // The factor stage restores the matrix it factors (a device copy per system, or one for
  // all in lockstep): timed separately and taken off.
  double restore_us(bool batched, int reps) {
    const size_t mz = size_t(m);
    return median_us(main, reps, {}, [&] {
      if (batched) HSI_CUDA_CHECK(cudaMemcpyAsync(Hr.get(), A0.get(), A0.bytes(), cudaMemcpyDeviceToDevice, main));
      else
        for (int s = 0; s < S; ++s)
          HSI_CUDA_CHECK(cudaMemcpyAsync(Hr.get() + size_t(s) * mz * mz, A0.get() + size_t(s) * mz * mz, mz * mz * sizeof(double),
                                         cudaMemcpyDeviceToDevice, main));
    });
  }
};

// Kernel launches (cuBLAS / cuSOLVER calls counted as one) per system and stage.
constexpr int kEachLaunches[kStages] = {3, 2, 3, 2, 7, 5, 5, 3, 2, 2, 1, 1, 1, 2};
constexpr int kLockstepLaunches[kStages] = {3, 3, 3, 2, 7, 5, 5, 3, 2, 2, 1, 1, 1, 2};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"What a lockstep batch of S systems of one setup would cost the GPU per warm frame, stage by stage (issue #23)"};
  std::vector<std::string> scenes = {"assets/bar_holes.json"};
  std::vector<int> systems = {1, 16, 64};
  int samples = 10000, reps = 20, streams = 16;
  bool tall = false, strided = false;
  double ratio = 0.2;
  app.add_option("scenes", scenes, "scene files (the setup of each; its first and last keyframes give the points)");
  app.add_option("--systems", systems, "batch sizes S")->delimiter(',');
  app.add_option("--samples", samples, "|G|");
  app.add_option("--ratio", ratio, "r = |H| / |G|");
  app.add_option("--reps", reps, "timed repetitions per stage (median)");
  app.add_option("--streams", streams, "streams for the one-system calls spread out (k str. column)");
  app.add_flag("--tall-products", tall, "lockstep's products D·[c_1 … c_S] by tall_times_two_batched (each system's bits "
               "as alone) instead of one ZGEMM");
  app.add_flag("--strided-hessian", strided, "lockstep's Hessian products as a strided-batched ZGEMM (D_H shared) instead of one "
               "ZGEMM over every system's weighted rows");
  CLI11_PARSE(app, argc, argv);
  std::string why;
  if (!hc::device_available(&why)) {
    std::fprintf(stderr, "bench_lockstep: no CUDA device: %s\n", why.c_str());
    return 1;
  }
  std::printf("# Lockstep batch: device µs per system and stage (%s)\n\n", hc::clocks().describe().c_str());
  std::printf("|G| = %d, r = %.2f; median of %d repetitions after 3 warm-up; each: one system's calls after another on one "
              "stream; %d str.: the same calls over %d streams; lockstep: one call per stage for all S systems "
              "(newton_kernels.h's *_batched, %s, %s, the reduced systems as strided-batched GEMMs, potrfBatched, cholesky_solve_batched, a DeviceCertifier "
              "for S maps). "
              "launches: kernels and library calls per system (each) and per batch (lockstep). Not included: the ridge and scalars "
              "between stages, the host.\n\n",
              samples, ratio, reps, streams, streams,
              tall ? "the products with D by tall_times_two_batched" : "the products with D as one ZGEMM over 2S columns",
              strided ? "the Hessians' products as one strided-batched ZGEMM" : "the Hessians' products as one ZGEMM over every system's weighted rows");
  for (const std::string& path : scenes) {
    bench::Loaded L = bench::load(path, samples, ratio);
    for (const int S : systems) {
      Bench b(*L.setup, L.maps, S, std::min(streams, S), tall, strided);
      std::printf("## %s, S = %d (n = %d, |G| = %d, |H| = %d, m = %d)\n\n", L.name.c_str(), S, b.n, b.G, b.h, b.m);
      std::printf("| stage | each µs/system | %d str. µs/system | lockstep µs/system | each / lockstep | %d str. / lockstep | "
                  "launches each (per system) | launches lockstep (per batch) |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
                  b.streams, b.streams);
      const double restore_each = b.restore_us(false, reps) / S, restore_batched = b.restore_us(true, reps) / S;
      double sum_each[2] = {0, 0}, sum_spread[2] = {0, 0}, sum_lock[2] = {0, 0};  // [over G, over H]
      for (int st = 0; st < kStages; ++st) {
        const Stage stage = static_cast<Stage>(st);
        double e = median_us(b.main, reps, {}, [&] { b.each(stage); });
        double k = median_us(b.main, reps, {}, [&] { b.spread(stage); });
        double l = median_us(b.main, reps, {}, [&] { b.lockstep(stage); });
        e /= S;
        k /= S;
        l /= S;
        std::printf("| %s | %.2f | %.2f | %.2f | %.1f× | %.1f× | %d | %d |\n", kStageNames[st], e, k, l, e / l, k / l, kEachLaunches[st],
                    kLockstepLaunches[st]);
        for (int over = 0; over < 2; ++over) {
          if ((stage == kExactG && over == 1) || (stage == kExactH && over == 0) || stage >= kRowsH) continue;
          sum_each[over] += e;
          sum_spread[over] += k;
          sum_lock[over] += l;
        }
      }
      for (int over = 0; over < 2; ++over)
        std::printf("| **a warm frame, exact system over %s** (the stages above, but the other exact system and the rows alone) | %.1f | %.1f | %.1f | %.1f× | "
                    "%.1f× | | |\n",
                    over == 0 ? "G" : "H", sum_each[over], sum_spread[over], sum_lock[over], sum_each[over] / sum_lock[over],
                    sum_spread[over] / sum_lock[over]);
      std::printf("\nThe factor row includes the copy that restores each matrix before it is factored: %.2f µs per system one "
                  "by one, %.2f in one copy for the batch (timed alone).\n",
                  restore_each, restore_batched);
      std::printf("\nframes/s if a frame cost the GPU only these stages: exact over G each %.0f, %d str. %.0f, lockstep %.0f; "
                  "over H each %.0f, %d str. %.0f, lockstep %.0f\n\n",
                  1e6 / sum_each[0], b.streams, 1e6 / sum_spread[0], 1e6 / sum_lock[0], 1e6 / sum_each[1], b.streams,
                  1e6 / sum_spread[1], 1e6 / sum_lock[1]);
      std::fflush(stdout);
    }
  }
  return 0;
}
