// DeviceBatchStepper (hsi/cuda/batch_stepper.h): DeviceStepper's calls (device_newton.cpp)
// for S systems of one setup, each kind of call served for every system of a batch
// together. Per-system arrays sit at fixed strides (system s at base + s · stride), so
// that the systems of a batch that are neighbours (a run: first … first + count − 1, the
// usual batch being all of them) are one launch of a *_batched kernel, one strided
// GEMM, one potrfBatched; the small one-block kernels are launched per system. The
// numbers every kernel writes for the host land in mapped pinned memory (as in
// DeviceStepper), the per-call numbers (ridges, steps) are read by the kernels from
// mapped pinned memory too, and each serve() ends with one synchronisation: no CUDA
// graphs (a batch's members change from call to call).
#include "hsi/cuda/batch_stepper.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <utility>

#include "cuda_newton_core.h"
#include "dense_cholesky.h"
#include "newton_kernels.h"

namespace hsi::cuda {

namespace {

using Kind = StepRequest::Kind;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kSteps = kernels::kMaxSteps;

// A system's scalar slots in the pinned `down` block (kSlots per system) and, for the
// statuses, in the device's `sc` block.
enum Slot { kSlope = 0, kGradNorm2, kDiagMax, kInfo, kSlots };

// A per-system device array: system s at base + s · stride.
template <class T>
struct Strided {
  DeviceArray<T> a;
  size_t stride = 0;
  Strided() = default;
  Strided(int systems, size_t per) : a(per * static_cast<size_t>(systems)), stride(per) {}
  T* at(int s) const { return a.get() + static_cast<size_t>(s) * stride; }
};

// Neighbouring systems of a sorted list: (first, count) runs.
std::vector<std::pair<int, int>> runs_of(const std::vector<int>& sys) {
  std::vector<std::pair<int, int>> out;
  for (int s : sys) {
    if (!out.empty() && out.back().first + out.back().second == s)
      ++out.back().second;
    else
      out.push_back({s, 1});
  }
  return out;
}

}  // namespace

class BatchDeviceStepper final : public DeviceBatchStepper {
 public:
  BatchDeviceStepper(const ShapeSetup& setup, int systems)
      : setup_(setup), S_(systems), core_(setup.D_G, setup.H, &setup), space_(core_.device_space(setup.metric_space)),
        cert_(setup, core_.stream_, core_.blas_, systems), state_(static_cast<size_t>(systems)) {
    const int G = core_.G_, n = core_.n_, h = core_.h_;
    dim_ = space_.dim;
    m1_ = dim_ + 1;
    n4_ = 4 * n;
    M4_ = space_.M4;
    blocks_ = static_cast<int>(kernels::reduction_blocks(G));
    const size_t m1 = sz(m1_), n4 = sz(n4_);
    g_ = Strided<double>(S_, 3 * sz(G));
    ab_ = Strided<double2>(S_, 2 * sz(G));
    dab_ = Strided<double2>(S_, 2 * sz(G));
    gab_ = Strided<double2>(S_, 2 * sz(G));
    coef_ = Strided<double2>(S_, 2 * sz(n));
    W_ = Strided<double2>(S_, 6 * sz(h));
    Wt_ = Strided<double2>(S_, sz(h) * 6 * sz(n));
    R_ = Strided<double2>(S_, 6 * sz(n) * sz(n));
    Hv_ = Strided<double>(S_, 16 * sz(n) * sz(n));
    part_sum_ = Strided<double>(S_, sz(kSteps) * sz(blocks_));
    part_bad_ = Strided<int>(S_, sz(kSteps) * sz(blocks_));
    done_ = Strided<unsigned>(S_, 1);
    xa_ = Strided<double>(S_, m1);
    xna_ = Strided<double>(S_, m1);
    gr_ = Strided<double>(S_, m1);
    d_ = Strided<double>(S_, m1);
    tmp_ = Strided<double>(S_, m1);
    ka_ = Strided<double>(S_, m1);
    v_ = Strided<double>(S_, n4);
    ku_ = Strided<double>(S_, n4);
    kuc_ = Strided<double>(S_, n4);
    Hr_ = Strided<double>(S_, m1 * m1);
    Hr0_ = Strided<double>(S_, m1 * m1);
    Hk_ = Strided<double>(S_, m1 * m1);
    Ta_ = Strided<double>(S_, n4 * m1);
    Tca_ = Strided<double>(S_, n4 * m1);
    Y_ = Strided<double>(S_, n4 * m1);
    full_ = Strided<double>(S_, sz(M4_));
    sc_ = Strided<double>(S_, kSlots);
    factor_info_ = DeviceArray<int>(sz(S_));
    down_ = PinnedArray<double>(sz(S_) * kSlots);
    x_up_ = PinnedArray<double>(sz(S_) * m1);
    x_down_ = PinnedArray<double>(sz(S_) * m1);
    energy0_ = PinnedArray<double>(sz(S_));
    energies_ = PinnedArray<double>(sz(S_) * kSteps);
    safe_ = PinnedArray<double>(sz(S_));
    zero_steps_ = PinnedArray<double>(sz(S_));
    steps_ = PinnedArray<double>(sz(S_) * kSteps);
    step_ = PinnedArray<double>(sz(S_));
    ridge_ = PinnedArray<double>(sz(S_));
    factor_info_down_ = PinnedArray<int>(sz(S_));
    std::fill_n(zero_steps_.get(), S_, 0.0);
    bytes_ = g_.a.bytes() + ab_.a.bytes() + dab_.a.bytes() + gab_.a.bytes() + coef_.a.bytes() + W_.a.bytes() + Wt_.a.bytes() +
             R_.a.bytes() + Hv_.a.bytes() + part_sum_.a.bytes() + part_bad_.a.bytes() + done_.a.bytes() + sc_.a.bytes() +
             full_.a.bytes() + (xa_.a.bytes() * 6) + Hr_.a.bytes() * 3 + Ta_.a.bytes() * 3 + v_.a.bytes() * 3;
    const cudaStream_t s = st();
    // Nothing read uninitialised (DeviceStepper's and the core's initial state): a = b = 0,
    // a zero direction, identity targets, x = 0, the counters 0.
    HSI_CUDA_CHECK(cudaMemsetAsync(ab_.a.get(), 0, ab_.a.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(dab_.a.get(), 0, dab_.a.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(done_.a.get(), 0, done_.a.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(xa_.a.get(), 0, xa_.a.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(xna_.a.get(), 0, xna_.a.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(d_.a.get(), 0, d_.a.bytes(), s));
    for (int k = 0; k < S_; ++k) {
      HSI_CUDA_CHECK(cudaMemcpyAsync(g_.at(k), core_.g_.get(), core_.g_.bytes(), cudaMemcpyDeviceToDevice, s));  // identity
      HSI_CUDA_CHECK(cudaMemcpyAsync(Ta_.at(k), space_.Ta.get(), space_.Ta.bytes(), cudaMemcpyDeviceToDevice, s));
      HSI_CUDA_CHECK(cudaMemcpyAsync(Tca_.at(k), space_.Tca.get(), space_.Tca.bytes(), cudaMemcpyDeviceToDevice, s));
    }
    // The factors' addresses for potrfBatched (fixed: the strides never change).
    std::vector<double*> ptrs(sz(S_));
    for (int k = 0; k < S_; ++k) ptrs[sz(k)] = Hr_.at(k);
    Hr_ptrs_ = DeviceArray<double*>(sz(S_));
    HSI_CUDA_CHECK(cudaMemcpyAsync(Hr_ptrs_.get(), ptrs.data(), Hr_ptrs_.bytes(), cudaMemcpyHostToDevice, s));
    HSI_CUDA_CHECK(cudaStreamSynchronize(s));  // ptrs is pageable
  }

  ~BatchDeviceStepper() override { cudaStreamSynchronize(st()); }

  int systems() const override { return S_; }

  void set_targets(int system, const std::vector<Metric>& g) override {
    check_system(system);
    const size_t G = sz(core_.G_);
    if (g.size() != G)
      throw InputError("hsi::cuda batch: " + std::to_string(g.size()) + " target metrics for " + std::to_string(G) + " samples");
    std::vector<double> flat(3 * G);
    for (size_t i = 0; i < G; ++i)
      for (int q = 0; q < 3; ++q) flat[3 * i + sz(q)] = g[i](q);
    // On a stream of its own, waited for: the system's next request is enqueued after it.
    std::lock_guard<std::mutex> lock(targets_mutex_);
    HSI_CUDA_CHECK(cudaMemcpyAsync(g_.at(system), flat.data(), flat.size() * sizeof(double), cudaMemcpyHostToDevice, targets_stream_));
    HSI_CUDA_CHECK(cudaStreamSynchronize(targets_stream_));
  }

  size_t device_bytes() const override { return bytes_; }

  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    if (&certifier != &setup_.certifier || !core_.certifier_) return std::nullopt;
    std::lock_guard<std::mutex> lock(serve_mutex_);  // the stream's cuBLAS handle is serve()'s too
    return core_.certifier_->certify(map);
  }

  void serve(Kind kind, std::span<StepRequest* const> batch) override {
    std::lock_guard<std::mutex> lock(serve_mutex_);
    for (StepRequest* r : batch)
      if (r->kind != kind || r->system < 0 || r->system >= S_)
        throw std::logic_error("hsi::cuda batch: a request for system " + std::to_string(r->system) + " of " + std::to_string(S_) +
                               " or of another kind");
    switch (kind) {
      case Kind::Start:
      case Kind::StartDeferred: by_shape(batch, [](const StepRequest&) { return 0; }, [&](auto& g) { start(g); }); break;
      case Kind::StartEnergy:
        for (StepRequest* r : batch) r->energy = energy0_[sz(r->system)];
        break;
      case Kind::Linearize:
        by_shape(batch, [](const StepRequest& r) { return choice_key(*r.choice); }, [&](auto& g) { linearize(g); });
        break;
      case Kind::Solve:
      case Kind::Decrement:
        by_shape(batch, [&](const StepRequest& r) { return solve_key(r); }, [&](auto& g) { solve(g); });
        break;
      case Kind::Direction:
        by_shape(batch, [&](const StepRequest& r) { return shape_key(state_[sz(r.system)]); }, [&](auto& g) { direction(g); });
        break;
      case Kind::TrialEnergies: trial_energies(batch); break;
      case Kind::CertifyAhead:
        for (StepRequest* r : batch) state_[sz(r->system)].ahead_step = r->number;  // certify() does the work
        break;
      case Kind::Certify:
        by_shape(batch, [&](const StepRequest& r) {
          return std::uint64_t{r.number != 0} | std::uint64_t{r.full} << 1 | std::uint64_t{state_[sz(r.system)].rotation} << 2;
        }, [&](auto& g) { certify(g); });
        break;
      case Kind::Accept:
        by_shape(batch, [&](const StepRequest& r) {
          const System& y = state_[sz(r.system)];
          return std::uint64_t{!(r.number == y.trial_step)} | std::uint64_t{y.rotation} << 1;
        }, [&](auto& g) { accept(g); });
        break;
      case Kind::X: by_shape(batch, [](const StepRequest&) { return 0; }, [&](auto& g) { x(g); }); break;
      case Kind::Keep: by_shape(batch, [](const StepRequest&) { return 0; }, [&](auto& g) { keep(g); }); break;
      case Kind::LinearizeKept: by_shape(batch, [](const StepRequest&) { return 0; }, [&](auto& g) { linearize_kept(g); }); break;
    }
  }

 private:
  // DeviceStepper's per-solve state, per system.
  struct System {
    int m = 0;
    bool rotation = false, horizontal = false, kept = false, exact = false, factored_exact = false;
    bool split = false;
    double diagonal_max = 0;
    bool x_down_valid = false;
    double ahead_step = kNaN, trial_step = kNaN;
    NewtonSystem pending;
    std::uint64_t kept_count = 0;
    int kept_order = 0;
    double kept_diagonal_max = 0;
  };
  using Group = std::vector<StepRequest*>;

  cudaStream_t st() const { return core_.stream_; }
  void check_system(int s) const {
    if (s < 0 || s >= S_) throw InputError("hsi::cuda batch: system " + std::to_string(s) + " of " + std::to_string(S_));
  }
  double* down(int s, Slot slot) const { return down_.get() + sz(s) * kSlots + slot; }
  int* info(int s) const { return reinterpret_cast<int*>(sc_.at(s) + kInfo); }  // [factor, solves]
  static std::vector<int> systems_of(const Group& g) {
    std::vector<int> out;
    for (const StepRequest* r : g) out.push_back(r->system);
    return out;
  }

  // The requests of one batch split by `key` (what changes the sequence of work), each
  // group served by `serve` in system order; an error reaches that group's requests.
  template <class Key, class Serve>
  void by_shape(std::span<StepRequest* const> batch, Key key, Serve serve) {
    std::map<std::uint64_t, Group> groups;
    for (StepRequest* r : batch) groups[static_cast<std::uint64_t>(key(*r))].push_back(r);
    for (auto& [k, g] : groups) {
      std::sort(g.begin(), g.end(), [](const StepRequest* a, const StepRequest* b) { return a->system < b->system; });
      try {
        serve(g);
      } catch (...) {
        for (StepRequest* r : g) r->error = std::current_exception();
      }
    }
  }

  static std::uint64_t choice_key(const HessianChoice& c) {
    return static_cast<std::uint64_t>(c.projection) | std::uint64_t{c.exact} << 2 | std::uint64_t{c.all_samples} << 3 |
           std::uint64_t{c.free_rotation} << 4;
  }
  static std::uint64_t shape_key(const System& y) {
    return static_cast<std::uint64_t>(y.m) << 8 | std::uint64_t{y.rotation} | std::uint64_t{y.horizontal} << 1 |
           std::uint64_t{y.kept} << 2;
  }
  std::uint64_t solve_key(const StepRequest& r) const {
    const System& y = state_[sz(r.system)];
    const bool split = r.kind == Kind::Decrement && !y.kept && space_.split_solve && kernels::cholesky_solve_in_cluster(y.m);
    return shape_key(y) | std::uint64_t{split} << 3;
  }

  // ab = D (Tc x) for each system (x from `from` when given, copied into xa in the same launch).
  void set_coefficients(const std::vector<int>& sys, const Strided<double>* from) {
    for (auto [first, count] : runs_of(sys)) {
      // Tc x with the space's Tc (every system's first dim columns of Tca are the same).
      kernels::TallOptions o;
      o.x_copy = from ? xa_.at(first) : nullptr;
      kernels::TallStrides b;
      b.x = b.x_copy = m1_;
      b.y = n4_;
      HSI_CUDA_CHECK(kernels::tall_times_one_batched(count, n4_, dim_, space_.Tca.get(), from ? from->at(first) : xa_.at(first),
                                                     reinterpret_cast<double*>(coef_.at(first)), st(), o, b));
      HSI_CUDA_CHECK(kernels::tall_times_two_batched(count, core_.G_, core_.n_, core_.D_, coef_.at(first), ab_.at(first), st()));
    }
  }

  void start(Group& g) {
    Group ok;
    for (StepRequest* r : g) {
      if (r->x0->size() != dim_) {
        r->error = std::make_exception_ptr(InputError("hsi::cuda: the start vector has " + std::to_string(r->x0->size()) +
                                                      " entries, the space " + std::to_string(dim_)));
        continue;
      }
      // [x0; 0]: the run's copy below takes m1 entries per system, and the last, the
      // freed rotation's slot, must be 0 (a trial point with the rotation freed is
      // Ta ([x; 0] + s d)). Left unwritten, it held whatever pinned memory the driver had
      // handed out before: trial points off by that multiple of u (the likely cause of
      // the frames that stopped on "no decrease" in solve_batch, H100, 2026-12-08).
      double* up = x_up_.get() + sz(r->system) * sz(m1_);
      std::copy(r->x0->data(), r->x0->data() + dim_, up);
      up[dim_] = 0;
      ok.push_back(r);
    }
    if (ok.empty()) return;
    const std::vector<int> sys = systems_of(ok);
    for (auto [first, count] : runs_of(sys))
      HSI_CUDA_CHECK(cudaMemcpyAsync(xa_.at(first), x_up_.get() + sz(first) * sz(m1_), sz(count) * sz(m1_) * sizeof(double),
                                     cudaMemcpyHostToDevice, st()));
    set_coefficients(sys, nullptr);
    for (auto [first, count] : runs_of(sys))
      HSI_CUDA_CHECK(kernels::mean_energies_batched(count, core_.G_, g_.at(first), ab_.at(first), dab_.at(first), zero_steps_.get() + first,
                                                    1, part_sum_.at(first), part_bad_.at(first), done_.at(first),
                                                    energy0_.get() + first, st()));
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    for (StepRequest* r : ok) {
      System& y = state_[sz(r->system)];
      y.trial_step = y.ahead_step = kNaN;
      y.x_down_valid = false;
      r->energy = energy0_[sz(r->system)];
    }
  }

  // The gradient at x for each system (m entries; with the rotation freed and `fresh`,
  // u = R T x first; with `horizontal`, its horizontal part in the kept frame).
  void gradient(const std::vector<int>& sys, bool fresh, bool horizontal) {
    const int G = core_.G_, n = core_.n_;
    for (auto [first, count] : runs_of(sys)) {
      if (state_[sz(first)].rotation && fresh) {  // (a linearize group shares its choice)
        kernels::TallOptions o;
        o.second_A = space_.RTc.get();
        o.second_rows = n4_;
        o.second_y = Tca_.at(first) + sz(n4_) * sz(dim_);
        kernels::TallStrides b;
        b.x = m1_;
        b.y = b.second_y = static_cast<long long>(n4_) * m1_;
        HSI_CUDA_CHECK(kernels::tall_times_one_batched(count, n4_, dim_, space_.RT.get(), xa_.at(first), Ta_.at(first) + sz(n4_) * sz(dim_),
                                                       st(), o, b));
      }
      HSI_CUDA_CHECK(kernels::gradient_samples_batched(count, G, g_.at(first), ab_.at(first), gab_.at(first), st()));
    }
    // [gφ | gψ] = Dᴴ [ga | gb] for every system of a run in one ZGEMM (D read once), then
    // g = Tcaᵀ (·) / |G| as a strided batch, and its horizontal part where asked.
    const int m = state_[sz(sys.front())].m;  // (a group shares its order)
    const double scale = 1 / static_cast<double>(G);
    const long long n4 = n4_, m1 = m1_;
    for (auto [first, count] : runs_of(sys)) {
      HSI_CUDA_CHECK(cublasZgemm(core_.blas_, CUBLAS_OP_C, CUBLAS_OP_N, n, 2 * count, G, &kOne, core_.D_, G, gab_.at(first), G, &kZero,
                                 coef_.at(first), n));
      HSI_CUDA_CHECK(cublasDgemmStridedBatched(core_.blas_, CUBLAS_OP_T, CUBLAS_OP_N, m, 1, n4_, &scale, Tca_.at(first), n4_, n4 * m1,
                                               reinterpret_cast<const double*>(coef_.at(first)), n4_, n4, &kZeroD, gr_.at(first), m, m1,
                                               count));
      if (horizontal) HSI_CUDA_CHECK(kernels::horizontal_gradient_batched(count, dim_, tmp_.at(first), gr_.at(first), m1, st()));
    }
  }

  void linearize(Group& g) {
    const HessianChoice& c = *g.front()->choice;
    const std::vector<int> sys = systems_of(g);
    for (int s : sys) {
      System& y = state_[sz(s)];
      y.kept = false;
      y.exact = c.exact;
      y.m = c.free_rotation ? dim_ + 1 : dim_;
      y.rotation = c.free_rotation;
      y.horizontal = y.rotation && c.exact;
    }
    if (c.all_samples) prepare_all_samples();
    gradient(sys, true, false);
    // The Hessian over H (or G) for every system: weights and rows in one launch, one
    // ZGEMM D_Hᴴ [Wt_first … Wt_last] (the systems' rows lie side by side), the real
    // Hessians in one launch; then Hr0 = Taᵀ Hv Ta as two strided-batched GEMMs.
    const int G = core_.G_, n = core_.n_, rows = c.all_samples ? G : core_.h_;
    const double2* DH = c.all_samples ? core_.D_ : core_.DH_;
    const int* index = c.all_samples ? all_index_.get() : core_.H_;
    Strided<double2>& W = c.all_samples ? W_all_ : W_;
    Strided<double2>& Wt = c.all_samples ? Wt_all_ : Wt_;
    const int m = state_[sz(sys.front())].m;
    const long long n4 = n4_, m1 = m1_;
    for (auto [first, count] : runs_of(sys)) {
      HSI_CUDA_CHECK(kernels::weighted_rows_batched(count, G, rows, n, index, g_.at(first), ab_.at(first), to_device(c.projection),
                                                    c.exact, DH, W.at(first), Wt.at(first), st()));
      HSI_CUDA_CHECK(cublasZgemm(core_.blas_, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n * count, rows, &kOne, DH, rows, Wt.at(first), rows,
                                 &kZero, R_.at(first), n));
      HSI_CUDA_CHECK(kernels::real_hessian_batched(count, n, R_.at(first), static_cast<double>(rows), Hv_.at(first), st()));
      HSI_CUDA_CHECK(cublasDgemmStridedBatched(core_.blas_, CUBLAS_OP_N, CUBLAS_OP_N, n4_, m, n4_, &kOneD, Hv_.at(first), n4_,
                                               16LL * n * n, Ta_.at(first), n4_, n4 * m1, &kZeroD, Y_.at(first), n4_, n4 * m1, count));
      HSI_CUDA_CHECK(cublasDgemmStridedBatched(core_.blas_, CUBLAS_OP_T, CUBLAS_OP_N, m, m, n4_, &kOneD, Ta_.at(first), n4_, n4 * m1,
                                               Y_.at(first), n4_, n4 * m1, &kZeroD, Hr0_.at(first), m, m1 * m1, count));
      if (state_[sz(first)].horizontal)  // a = Tᵀu (with |u|² last) for the system modulo the rotation
        HSI_CUDA_CHECK(cublasDgemmStridedBatched(core_.blas_, CUBLAS_OP_T, CUBLAS_OP_N, m, 1, n4_, &kOneD, Ta_.at(first), n4_, n4 * m1,
                                                 Ta_.at(first) + n4 * dim_, n4_, n4 * m1, &kZeroD, tmp_.at(first), m, m1, count));
    }
    for (auto [first, count] : runs_of(sys)) {
      if (state_[sz(first)].horizontal)
        HSI_CUDA_CHECK(kernels::horizontal_system_batched(count, dim_, Hr0_.at(first), m1 * m1, tmp_.at(first), gr_.at(first), m1,
                                                          sc_.at(first) + kDiagMax, kSlots, st()));
      else
        HSI_CUDA_CHECK(kernels::diag_abs_max_batched(count, m, Hr0_.at(first), m1 * m1, sc_.at(first) + kDiagMax, kSlots, st()));
    }
    // Not waited for: the solve that follows synchronises.
  }

  void prepare_all_samples() {
    if (all_index_.get()) return;
    const int G = core_.G_, n = core_.n_;
    std::vector<int> iota(sz(G));
    for (size_t i = 0; i < iota.size(); ++i) iota[i] = static_cast<int>(i);
    W_all_ = Strided<double2>(S_, 6 * sz(G));
    Wt_all_ = Strided<double2>(S_, sz(G) * 6 * sz(n));
    bytes_ += W_all_.a.bytes() + Wt_all_.a.bytes();
    all_index_ = DeviceArray<int>(sz(G));
    HSI_CUDA_CHECK(cudaMemcpyAsync(all_index_.get(), iota.data(), all_index_.bytes(), cudaMemcpyHostToDevice, st()));
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));  // iota is pageable
  }

  void solve(Group& g) {
    const std::vector<int> sys = systems_of(g);
    const System& y0 = state_[sz(sys.front())];
    const int m = y0.m;
    const bool kept = y0.kept;
    const bool split = (solve_key(*g.front()) >> 3) & 1;
    const long long m1 = m1_;
    for (StepRequest* r : g) {
      System& y = state_[sz(r->system)];
      y.factored_exact = false;
      ridge_[sz(r->system)] = r->number;
    }
    for (auto [first, count] : runs_of(sys))  // x down, for x() without a wait
      HSI_CUDA_CHECK(cudaMemcpyAsync(x_down_.get() + sz(first) * sz(m1_), xa_.at(first), sz(count) * sz(m1_) * sizeof(double),
                                     cudaMemcpyDeviceToHost, st()));
    for (auto [first, count] : runs_of(sys)) {
      if (!kept)
        HSI_CUDA_CHECK(kernels::add_relative_ridge_batched(count, m, Hr0_.at(first), Hr_.at(first), m1 * m1, ridge_.get() + first, 1,
                                                           sc_.at(first) + kDiagMax, down(first, kDiagMax), kSlots, st()));
      HSI_CUDA_CHECK(kernels::negate_batched(count, m, gr_.at(first), d_.at(first), m1, info(first), 2 * kSlots, st()));
    }
    Strided<double>& L = kept ? Hk_ : Hr_;
    for (auto [first, count] : runs_of(sys)) {
      if (!kept) {
        HSI_CUDA_CHECK(cusolverDnDpotrfBatched(core_.solver_, CUBLAS_FILL_MODE_LOWER, m, Hr_ptrs_.get() + first, m,
                                               factor_info_.get() + first, count));
        HSI_CUDA_CHECK(cudaMemcpyAsync(factor_info_down_.get() + first, factor_info_.get() + first, sz(count) * sizeof(int),
                                       cudaMemcpyDeviceToHost, st()));
      }
      HSI_CUDA_CHECK(kernels::cholesky_solve_batched(m, L.at(first), m, m1 * m1, d_.at(first), m1, count, st(),
                                                     split ? kernels::Substitution::Forward : kernels::Substitution::Both));
    }
    if (split) {
      for (auto [first, count] : runs_of(sys))
        HSI_CUDA_CHECK(kernels::decrement_scalars_batched(count, dim_, m, gr_.at(first), d_.at(first), m1, down(first, kSlope),
                                                          down(first, kGradNorm2), kSlots, info(first),
                                                          reinterpret_cast<int*>(down(first, kInfo)), 2 * kSlots, st()));
    } else {
      enqueue_direction(sys);
    }
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    for (StepRequest* r : g) {
      const int s = r->system;
      System& y = state_[sz(s)];
      y.trial_step = y.ahead_step = kNaN;
      y.x_down_valid = true;
      NewtonSystem sys_out;
      sys_out.diagonal_max = kept ? y.kept_diagonal_max : *down(s, kDiagMax);
      if (!kept) y.diagonal_max = sys_out.diagonal_max;
      sys_out.gradient_norm = std::sqrt(*down(s, kGradNorm2));
      sys_out.slope = *down(s, kSlope);
      const int factor_status = kept ? 0 : factor_info_down_[sz(s)];
      sys_out.factored = factor_status == 0 && std::isfinite(sys_out.slope);
      y.factored_exact = sys_out.factored && y.exact && !kept;
      if (split) {
        sys_out.max_safe_step = kNaN;
        sys_out.has_direction = false;
      } else {
        read_direction(s, sys_out);
      }
      y.pending = sys_out;
      r->system_result = sys_out;
    }
  }

  void read_direction(int s, NewtonSystem& sys) const {
    sys.slope = *down(s, kSlope);
    sys.max_safe_step = safe_[sz(s)];
    sys.factored = sys.factored && std::isfinite(sys.slope);
  }

  // After the triangular solves, for each system: θ's share (modulo the rotation), the
  // slope and |g|², d in the samples and the safe step along it.
  void enqueue_direction(const std::vector<int>& sys) {
    const int G = core_.G_, n = core_.n_;
    const int m = state_[sz(sys.front())].m;
    const long long n4 = n4_, m1 = m1_;
    for (auto [first, count] : runs_of(sys)) {
      HSI_CUDA_CHECK(kernels::step_scalars_batched(count, dim_, m, state_[sz(first)].horizontal, tmp_.at(first), gr_.at(first), d_.at(first),
                                                   m1, down(first, kSlope), down(first, kGradNorm2), kSlots, st()));
      // [dφ | dψ] = Tca d for each system (coef is 2n complex = 4n reals per system).
      HSI_CUDA_CHECK(cublasDgemmStridedBatched(core_.blas_, CUBLAS_OP_N, CUBLAS_OP_N, n4_, 1, m, &kOneD, Tca_.at(first), n4_, n4 * m1,
                                               d_.at(first), m, m1, &kZeroD, reinterpret_cast<double*>(coef_.at(first)), n4_, n4,
                                               count));
      HSI_CUDA_CHECK(kernels::tall_times_two_batched(count, G, n, core_.D_, coef_.at(first), dab_.at(first), st()));
      HSI_CUDA_CHECK(kernels::max_safe_step_batched(count, G, ab_.at(first), dab_.at(first), part_sum_.at(first), done_.at(first),
                                                    safe_.get() + first, st()));
    }
  }

  void direction(Group& g) {
    const std::vector<int> sys = systems_of(g);
    for (StepRequest* r : g) {
      const System& y = state_[sz(r->system)];
      if (!y.pending.factored || y.pending.has_direction)
        throw std::logic_error("hsi::cuda batch: direction() without a split decrement()");
    }
    const int m = state_[sz(sys.front())].m;
    const long long m1 = m1_;
    for (auto [first, count] : runs_of(sys))
      HSI_CUDA_CHECK(kernels::cholesky_solve_batched(m, Hr_.at(first), m, m1 * m1, d_.at(first), m1, count, st(),
                                                     kernels::Substitution::Back));
    enqueue_direction(sys);
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    for (StepRequest* r : g) {
      System& y = state_[sz(r->system)];
      NewtonSystem out = y.pending;
      y.pending.has_direction = true;
      out.has_direction = true;
      read_direction(r->system, out);
      r->system_result = out;
    }
  }

  void trial_energies(std::span<StepRequest* const> batch) {
    // In rounds of at most kSteps steps per system; a round's systems with the same count
    // of steps together.
    for (size_t begin = 0;; begin += kSteps) {
      std::map<int, Group> by_count;
      for (StepRequest* r : batch)
        if (!r->error && r->steps.size() > begin) by_count[static_cast<int>(std::min<size_t>(kSteps, r->steps.size() - begin))].push_back(r);
      if (by_count.empty()) return;
      for (auto& [count, g] : by_count) {
        std::sort(g.begin(), g.end(), [](const StepRequest* a, const StepRequest* b) { return a->system < b->system; });
        try {
          for (StepRequest* r : g)
            std::copy_n(r->steps.begin() + static_cast<std::ptrdiff_t>(begin), count, steps_.get() + sz(r->system) * sz(count));
          for (auto [first, runs] : runs_of(systems_of(g)))
            HSI_CUDA_CHECK(kernels::mean_energies_batched(runs, core_.G_, g_.at(first), ab_.at(first), dab_.at(first),
                                                          steps_.get() + sz(first) * sz(count), count, part_sum_.a.get() + sz(first) * sz(count) * sz(blocks_),
                                                          part_bad_.a.get() + sz(first) * sz(count) * sz(blocks_), done_.at(first),
                                                          energies_.get() + sz(first) * sz(count), st()));
          HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
          for (StepRequest* r : g)
            for (int j = 0; j < count; ++j) r->energies[begin + sz(j)] = energies_[sz(r->system) * sz(count) + sz(j)];
        } catch (...) {
          for (StepRequest* r : g) r->error = std::current_exception();
        }
      }
    }
  }

  // xna = x ⊕ step·d for each system of a group (one rotation setting), the steps read
  // from step_.
  void enqueue_trial(const std::vector<int>& sys) {
    const long long m1 = m1_, n4 = n4_;
    for (auto [first, count] : runs_of(sys)) {
      if (!state_[sz(first)].rotation) {
        HSI_CUDA_CHECK(kernels::trial_point_batched(count, dim_, xa_.at(first), d_.at(first), xna_.at(first), m1, step_.get() + first, 1, st()));
        continue;
      }
      kernels::TallOptions o;
      o.dx = d_.at(first);
      o.step = step_.get() + first;
      kernels::TallStrides b;
      b.A = n4 * m1;
      b.x = b.dx = m1;
      b.step = 1;
      b.y = n4;
      HSI_CUDA_CHECK(kernels::tall_times_one_batched(count, n4_, m1_, Ta_.at(first), xa_.at(first), v_.at(first), st(), o, b));
      HSI_CUDA_CHECK(kernels::regauge_batched(count, dim_, core_.n_, space_.rotation_vertex, space_.primary.get(), v_.at(first), n4,
                                              xna_.at(first), m1, st()));
    }
  }

  void certify(Group& g) {
    const bool trial = g.front()->number != 0, full = g.front()->full;
    const std::vector<int> sys = systems_of(g);
    for (StepRequest* r : g) {
      state_[sz(r->system)].ahead_step = kNaN;
      if (trial) step_[sz(r->system)] = r->number;
    }
    if (trial) enqueue_trial(sys);
    for (auto [first, count] : runs_of(sys)) {  // the full coefficients X0 + X x
      kernels::TallOptions expand;
      expand.y0 = space_.X0.get();
      kernels::TallStrides b;
      b.x = m1_;
      b.y = M4_;
      HSI_CUDA_CHECK(kernels::tall_times_one_batched(count, M4_, dim_, space_.X.get(), trial ? xna_.at(first) : xa_.at(first),
                                                     full_.at(first), st(), expand, b));
    }
    CertificateOptions o;
    o.stop_at_first_failure = !full;
    size_t k = 0;
    for (auto [first, count] : runs_of(sys)) {
      cert_.enqueue(reinterpret_cast<const double2*>(full_.at(first)), o, count);
      std::vector<CertificateResult> results = cert_.fetch_all(count);
      for (CertificateResult& c : results) g[k++]->certificate = std::move(c);
    }
    if (trial)
      for (StepRequest* r : g) state_[sz(r->system)].trial_step = r->number;
  }

  void accept(Group& g) {
    const bool trial = !(g.front()->number == state_[sz(g.front()->system)].trial_step);
    for (StepRequest* r : g) {
      state_[sz(r->system)].ahead_step = kNaN;
      if (trial) step_[sz(r->system)] = r->number;
    }
    if (trial) enqueue_trial(systems_of(g));
    set_coefficients(systems_of(g), &xna_);  // and x ← xna
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));  // step_ is free again
    for (StepRequest* r : g) {
      System& y = state_[sz(r->system)];
      y.trial_step = kNaN;
      y.x_down_valid = false;
    }
  }

  void x(Group& g) {
    bool wait = false;
    for (StepRequest* r : g) {
      const int s = r->system;
      if (state_[sz(s)].x_down_valid) continue;
      HSI_CUDA_CHECK(cudaMemcpyAsync(x_up_.get() + sz(s) * sz(m1_), xa_.at(s), sz(dim_) * sizeof(double), cudaMemcpyDeviceToHost, st()));
      wait = true;
    }
    if (wait) HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    for (StepRequest* r : g) {
      const int s = r->system;
      const double* from = (state_[sz(s)].x_down_valid ? x_down_.get() : x_up_.get()) + sz(s) * sz(m1_);
      r->x = Eigen::Map<const Eigen::VectorXd>(from, dim_);
    }
  }

  void keep(Group& g) {
    for (StepRequest* r : g) {
      const int s = r->system;
      System& y = state_[sz(s)];
      r->ok = false;
      if (!y.factored_exact || y.kept) continue;
      kernels::CopyList copies;
      copies.entry[0] = {Hr_.at(s), Hk_.at(s), sz(y.m) * sz(y.m)};
      int entries = 1;
      if (y.horizontal) {
        const size_t n4 = sz(n4_);
        copies.entry[1] = {Ta_.at(s) + n4 * sz(dim_), ku_.at(s), n4};
        copies.entry[2] = {Tca_.at(s) + n4 * sz(dim_), kuc_.at(s), n4};
        copies.entry[3] = {tmp_.at(s), ka_.at(s), sz(y.m)};
        entries = 4;
      }
      HSI_CUDA_CHECK(kernels::copy(copies, entries, st()));
      y.kept_order = y.m;
      y.kept_diagonal_max = y.diagonal_max;
      KeptSystem& slot = *r->slot;
      slot.owner = &y;
      slot.generation = ++y.kept_count;
      slot.data.reset();
      slot.order = y.m;
      slot.free_rotation = y.rotation;
      slot.modulo_rotation = y.horizontal;
      y.factored_exact = false;
      r->ok = true;
    }
    // (the copies run before any later call's work on the same stream)
  }

  void linearize_kept(Group& g) {
    Group ok;
    for (StepRequest* r : g) {
      const int s = r->system;
      System& y = state_[sz(s)];
      const KeptSystem& slot = *r->kept;
      r->ok = slot.owner == &y && slot.generation == y.kept_count && slot.order == y.kept_order &&
              slot.modulo_rotation == slot.free_rotation && slot.order == (slot.free_rotation ? dim_ + 1 : dim_);
      if (!r->ok) continue;
      y.kept = true;
      y.exact = false;
      y.m = slot.order;
      y.rotation = y.horizontal = slot.free_rotation;
      ok.push_back(r);
    }
    // Those with the rotation freed first take the kept system's frame, then every
    // system's gradient (horizontal where the rotation is freed).
    std::vector<int> with, without;
    for (StepRequest* r : ok) (state_[sz(r->system)].rotation ? with : without).push_back(r->system);
    for (int s : with) {
      const size_t n4 = sz(n4_);
      kernels::CopyList copies;
      copies.entry[0] = {ku_.at(s), Ta_.at(s) + n4 * sz(dim_), n4};
      copies.entry[1] = {kuc_.at(s), Tca_.at(s) + n4 * sz(dim_), n4};
      copies.entry[2] = {ka_.at(s), tmp_.at(s), sz(dim_ + 1)};
      HSI_CUDA_CHECK(kernels::copy(copies, 3, st()));
    }
    if (!with.empty()) gradient(with, false, true);
    if (!without.empty()) gradient(without, false, false);
  }

  static constexpr cuDoubleComplex kOne{1, 0}, kZero{0, 0};
  static constexpr double kOneD = 1, kZeroD = 0;

  const ShapeSetup& setup_;
  int S_;
  CudaNewtonCore core_;  // the stream, handles, D, D_H and H, the space's constant matrices
  DeviceSpace& space_;   // core_'s device space for setup_.metric_space: T, R T, X, X0, primary rows
  DeviceCertifier cert_; // capacity S_
  std::vector<System> state_;
  int dim_ = 0, m1_ = 0, n4_ = 0, M4_ = 0, blocks_ = 0;
  size_t bytes_ = 0;
  Strided<double> g_;
  Strided<double2> ab_, dab_, gab_, coef_, W_, Wt_, R_, W_all_, Wt_all_;
  Strided<double> Hv_, part_sum_;
  Strided<int> part_bad_;
  Strided<unsigned> done_;
  Strided<double> xa_, xna_, gr_, d_, tmp_, ka_, v_, ku_, kuc_, Hr_, Hr0_, Hk_, Ta_, Tca_, Y_, full_, sc_;
  DeviceArray<int> all_index_;
  DeviceArray<int> factor_info_;
  DeviceArray<double*> Hr_ptrs_;
  PinnedArray<double> down_, x_up_, x_down_, energy0_, energies_, safe_, zero_steps_, steps_, step_, ridge_;
  PinnedArray<int> factor_info_down_;
  Stream targets_stream_;
  std::mutex targets_mutex_;
  std::mutex serve_mutex_;  // serve() and certify_map() (one stream, one cuBLAS handle)
};

std::unique_ptr<DeviceBatchStepper> make_batch_stepper(const ShapeSetup& setup, int systems) {
  if (systems < 1 || systems > kernels::kMaxBatchSystems)
    throw InputError("hsi::cuda batch: " + std::to_string(systems) + " systems (1 to " + std::to_string(kernels::kMaxBatchSystems) + ")");
  return std::make_unique<BatchDeviceStepper>(setup, systems);
}

}  // namespace hsi::cuda
