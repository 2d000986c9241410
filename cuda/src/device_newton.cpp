// DeviceStepper: newton_solve's reduced-space work (engine/src/newton.cpp) with every
// vector on the GPU. The loop and all its decisions are the engine's; this file only
// computes. Per linearize: the gradient (tall products with D, newton_kernels.h), the Hessian as asked (kernels +
// ZGEMM), the reduced system [T u]ᵀ Hv [T u]; per solve: the Cholesky factor and solve
// (dense_cholesky.h, or cuSOLVER), the direction in the samples and the maximal safe step, one download of
// a few scalars; trial energies a batch of steps per download; the certificate of a
// trial map (certify_kernels.cu). x, d and the system never leave the device. Each call
// is one CUDA graph (GraphCache, device.h), captured on its first run per call shape
// and replayed after: per-call numbers (the ridge, the steps) reach it through pinned
// slots it copies from, and nothing inside a call waits for the host; a call then
// synchronises once, to hand back its few scalars.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "cuda_newton_core.h"
#include "dense_cholesky.h"
#include "newton_kernels.h"

namespace hsi::cuda {

namespace {
constexpr int kBatch = kernels::kMaxSteps;  // trial energies per download (NewtonStepper asks for up to this many)
// Scalar slots, one index space for DeviceSpace::sc (device) and sc_down (pinned host).
// The results before kTrials + kBatch are written by the kernels straight into sc_down
// (down()), except kInfo, which potrf and potrs write in sc and step_scalars copies down,
// and kDiagMax, which linearize writes in sc and the solve's ridge kernel copies down; the
// per-call numbers from kRidge on are copied into sc from DeviceSpace::params.
enum Slot {
  kSlope = 0,
  kGradNorm2 = 1,
  kSafeStep = 2,
  kDiagMax = 3,
  kEnergy0 = 4,
  kQuad0 = 5,  // ½xᵀQx + cᵀx (host adds k)
  kQuad1 = 6,  // (Q x + c)ᵀ d
  kQuad2 = 7,  // dᵀ Q d
  kScratch = 8,
  kInfo = 9,  // two ints: the factor's and the triangular solves' status
  kTrials = 10,
  kRidge = kTrials + kBatch,  // the per-call numbers, copied in from DeviceSpace::params
  kStep = kRidge + 1,
  kSteps = kStep + 1,
  kSlots = kSteps + kBatch
};
// DeviceSpace::params (pinned) mirrors sc from kRidge on.
constexpr int kParams = kSlots - kRidge;
constexpr int param(Slot s) { return s - kRidge; }

// Graph keys: the call, then what changes its sequence of work.
enum Call : std::uint64_t { kStart = 1, kLinearize, kSolve, kTrialEnergies, kCertify, kAccept, kLinearizeKept, kDirection };
std::uint64_t key(Call call, std::uint64_t shape) { return call | shape << 8; }

// The rotation generator applied to rows: in v layout (Re φ, Im φ, Re ψ, Im ψ blocks of n)
// u = (−Im φ, Re φ, Im ψ, −Re ψ); in complex order (Re φ_j, Im φ_j at 2j, 2j+1; ψ at 2n+2j…)
// the same per pair. R·A for a matrix A with 4n rows in either layout.
Eigen::MatrixXd rotate_rows(const Eigen::MatrixXd& A, int n, bool complex_order) {
  Eigen::MatrixXd out(A.rows(), A.cols());
  for (int j = 0; j < n; ++j) {
    const int rp = complex_order ? 2 * j : j, ip = complex_order ? 2 * j + 1 : n + j;
    const int rq = complex_order ? 2 * n + 2 * j : 2 * n + j, iq = complex_order ? 2 * n + 2 * j + 1 : 3 * n + j;
    out.row(rp) = -A.row(ip);
    out.row(ip) = A.row(rp);
    out.row(rq) = A.row(iq);
    out.row(iq) = -A.row(rq);
  }
  return out;
}
}  // namespace

CudaNewtonCore::~CudaNewtonCore() { cudaStreamSynchronize(stream_); }

DeviceSpace& CudaNewtonCore::device_space(const MapSpace& space) {
  auto& slot = spaces_[&space];
  if (slot) return *slot;
  auto ds = std::make_unique<DeviceSpace>();
  const int dim = space.dim(), n = n_;
  if (space.n() != n) throw InputError("hsi::cuda: the map space has " + std::to_string(space.n()) + " active columns, the core " + std::to_string(n));
  const int M = space.full_size();
  const int m = dim + 1;  // room for the freed rotation
  ds->dim = dim;
  ds->n4 = 4 * n;
  ds->M4 = 4 * M;
  ds->rotation_vertex = space.rotation_vertex();
  const Eigen::MatrixXd T = Eigen::MatrixXd(space.T());
  // Tc: row 2j ← Re φ_j (row j of T), 2j+1 ← Im φ_j (n + j), 2n+2j ← Re ψ_j, 2n+2j+1 ← Im ψ_j.
  Eigen::MatrixXd Tc(4 * n, dim);
  for (int j = 0; j < n; ++j) {
    Tc.row(2 * j) = T.row(j);
    Tc.row(2 * j + 1) = T.row(n + j);
    Tc.row(2 * n + 2 * j) = T.row(2 * n + j);
    Tc.row(2 * n + 2 * j + 1) = T.row(3 * n + j);
  }
  // Ta = [T | u], Tca = [Tc | u in complex order]; the last columns are rewritten by
  // linearize() when the rotation is freed (u = R T x).
  Eigen::MatrixXd Ta = Eigen::MatrixXd::Zero(4 * n, m), Tca = Eigen::MatrixXd::Zero(4 * n, m);
  Ta.leftCols(dim) = T;
  Tca.leftCols(dim) = Tc;
  const Eigen::MatrixXd RT = rotate_rows(T, n, false), RTc = rotate_rows(Tc, n, true);
  // expand() is affine in x: probe it at 0 and at each unit vector.
  auto flat = [&](const HarmonicMap& h) {
    Eigen::VectorXd v(4 * M);
    for (int j = 0; j < M; ++j) {
      v(2 * j) = h.phi(j).real();
      v(2 * j + 1) = h.phi(j).imag();
      v(2 * M + 2 * j) = h.psi(j).real();
      v(2 * M + 2 * j + 1) = h.psi(j).imag();
    }
    return v;
  };
  Eigen::VectorXd e = Eigen::VectorXd::Zero(dim);
  const Eigen::VectorXd x0 = flat(space.expand(e));
  Eigen::MatrixXd X(4 * M, dim);
  for (int k = 0; k < dim; ++k) {
    e.setZero();
    e(k) = 1;
    X.col(k) = flat(space.expand(e)) - x0;
  }
  // On the core's stream: a plain cudaMemcpy from pageable memory runs on the legacy
  // default stream and may return before its DMA lands, and kernels on a non-blocking
  // stream are not ordered after it. (The sources live until the synchronisation below.)
  auto upload = [&](DeviceArray<double>& dst, const double* src, size_t count) {
    dst = DeviceArray<double>(count);
    HSI_CUDA_CHECK(cudaMemcpyAsync(dst.get(), src, count * sizeof(double), cudaMemcpyHostToDevice, stream_));
  };
  upload(ds->Ta, Ta.data(), static_cast<size_t>(Ta.size()));
  upload(ds->Tca, Tca.data(), static_cast<size_t>(Tca.size()));
  upload(ds->RT, RT.data(), static_cast<size_t>(RT.size()));
  upload(ds->RTc, RTc.data(), static_cast<size_t>(RTc.size()));
  upload(ds->X, X.data(), static_cast<size_t>(X.size()));
  upload(ds->X0, x0.data(), static_cast<size_t>(x0.size()));
  ds->primary = DeviceArray<int>(sz(dim));
  HSI_CUDA_CHECK(cudaMemcpyAsync(ds->primary.get(), space.primary_rows().data(), ds->primary.bytes(), cudaMemcpyHostToDevice, stream_));
  const size_t D = sz(m);
  ds->xa = DeviceArray<double>(D);  // [x; 0]
  ds->xna = DeviceArray<double>(D);
  ds->g = DeviceArray<double>(D);
  ds->d = DeviceArray<double>(D);
  ds->tmp = DeviceArray<double>(D);
  ds->v = DeviceArray<double>(4 * sz(n));
  ds->Hr = DeviceArray<double>(D * D);
  ds->Hr0 = DeviceArray<double>(D * D);
  ds->Hk = DeviceArray<double>(D * D);
  ds->ku = DeviceArray<double>(4 * sz(n));
  ds->kuc = DeviceArray<double>(4 * sz(n));
  ds->ka = DeviceArray<double>(D);
  ds->Y = DeviceArray<double>(4 * sz(n) * D);
  ds->full = DeviceArray<double>(4 * sz(M));
  ds->sc = DeviceArray<double>(kSlots);
  ds->sc_down = PinnedArray<double>(kSlots);
  ds->params = PinnedArray<double>(kParams);
  ds->x_up = PinnedArray<double>(D);
  ds->x_down = PinnedArray<double>(D);
  HSI_CUDA_CHECK(cudaMemsetAsync(ds->xa.get(), 0, ds->xa.bytes(), stream_));
  HSI_CUDA_CHECK(cudaMemsetAsync(ds->xna.get(), 0, ds->xna.bytes(), stream_));
  HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(solver_, CUBLAS_FILL_MODE_LOWER, m, ds->Hr.get(), m, &ds->lwork));
  ds->work = DeviceArray<double>(sz(std::max(1, ds->lwork)));
  // The sizes that pick the kernels (cuBLAS's by shape): the same on every core of a shape.
  ds->graphs.set_signature({current_device(), G_, n, h_, dim, M, ds->lwork});
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
  slot = std::move(ds);
  return *slot;
}

class DeviceStepper final : public NewtonStepper {
 public:
  DeviceStepper(CudaNewtonCore& core, DeviceSpace& S, const QuadraticTerm* quad, bool certify)
      : c_(core), S_(S), quad_(quad), certify_(certify) {
    if (quad_) {
      const int dim = S_.dim;
      if (quad_->Q.rows() != dim || quad_->Q.cols() != dim || quad_->c.size() != dim)
        throw InputError("hsi::cuda: the quadratic term does not match the space");
      if (S_.Q.size() != sz(dim) * sz(dim)) {  // once per space: the graphs keep these addresses
        S_.Q = DeviceArray<double>(sz(dim) * sz(dim));
        S_.c = DeviceArray<double>(sz(dim));
      }
      HSI_CUDA_CHECK(cudaMemcpyAsync(S_.Q.get(), quad_->Q.data(), S_.Q.bytes(), cudaMemcpyHostToDevice, st()));
      HSI_CUDA_CHECK(cudaMemcpyAsync(S_.c.get(), quad_->c.data(), S_.c.bytes(), cudaMemcpyHostToDevice, st()));
    }
  }

  double start(const Eigen::VectorXd& x0) override {
    start_deferred(x0);
    return start_energy();
  }

  // The start's graph, not waited for: start_energy() reads its energy after the next
  // wait (the chord's solve, in newton_run), or waits itself.
  void start_deferred(const Eigen::VectorXd& x0) override {
    const int dim = S_.dim;
    if (x0.size() != dim) throw InputError("hsi::cuda: the start vector has " + std::to_string(x0.size()) + " entries, the space " + std::to_string(dim));
    std::copy(x0.data(), x0.data() + dim, S_.x_up.get());
    S_.graphs.run(key(kStart, 0), st(), [&] {
      HSI_CUDA_CHECK(cudaMemcpyAsync(S_.xa.get(), S_.x_up.get(), sz(dim) * sizeof(double), cudaMemcpyHostToDevice, st()));
      set_coefficients();
      HSI_CUDA_CHECK(kernels::mean_energy(c_.G_, c_.g_.get(), c_.ab_.get(), c_.dab_.get(), 0.0, c_.part_sum_.get(),
                                          c_.part_bad_.get(), c_.done_.get(), down(kEnergy0), st()));
    });
    trial_step_ = ahead_step_ = std::numeric_limits<double>::quiet_NaN();
    x_down_valid_ = false;
    start_quad_ = quad_ ? quad_->value(x0) : 0.0;
    start_pending_ = true;
  }

  double start_energy() override {
    // x_up is free again once the start's graph has run: the next start writes it.
    if (start_pending_) HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    start_pending_ = false;
    return S_.sc_down[kEnergy0] + start_quad_;
  }

  void linearize(const HessianChoice& choice) override {
    const int dim = S_.dim;
    kept_ = false;
    exact_ = choice.exact;
    m_ = choice.free_rotation ? dim + 1 : dim;
    rotation_ = choice.free_rotation;
    horizontal_ = rotation_ && choice.exact && !quad_;
    if (choice.all_samples) c_.prepare_all_samples();  // its buffers are made outside any graph
    const std::uint64_t shape = static_cast<std::uint64_t>(choice.projection) | std::uint64_t{choice.exact} << 2 |
                                std::uint64_t{choice.all_samples} << 3 | std::uint64_t{rotation_} << 4 |
                                std::uint64_t{quad_ != nullptr} << 5;
    // Not waited for: the solve that follows reads max |diag H| on the device (its
    // relative ridge), so the host's timing counts this work in that call.
    S_.graphs.run(key(kLinearize, shape), st(), [&] { enqueue_linearize(choice); });
  }

  bool linearize_kept(const KeptSystem& slot) override {
    const int dim = S_.dim;
    if (slot.owner != &S_ || slot.generation != S_.kept_count || slot.order != S_.kept_order) return false;
    if (slot.modulo_rotation != slot.free_rotation || (slot.free_rotation && quad_)) return false;
    if (slot.order != (slot.free_rotation ? dim + 1 : dim)) return false;
    kept_ = true;
    exact_ = false;
    m_ = slot.order;
    rotation_ = horizontal_ = slot.free_rotation;
    const std::uint64_t shape = std::uint64_t{rotation_} | std::uint64_t{quad_ != nullptr} << 1;
    S_.graphs.run(key(kLinearizeKept, shape), st(), [&] {
      // In the kept system's own rotation frame (NewtonOptions::kept_system; the host
      // stepper's linearize_kept): its u as the last columns of Ta and Tca, its a = Tᵀu
      // and |u|² (tmp), then the gradient and its horizontal part.
      if (rotation_) {
        const size_t n4 = 4 * sz(c_.n_);
        kernels::CopyList copies;
        copies.entry[0] = {S_.ku.get(), S_.Ta.get() + n4 * sz(dim), n4};
        copies.entry[1] = {S_.kuc.get(), S_.Tca.get() + n4 * sz(dim), n4};
        copies.entry[2] = {S_.ka.get(), S_.tmp.get(), sz(m_)};
        HSI_CUDA_CHECK(kernels::copy(copies, 3, st()));
      }
      enqueue_gradient(/*fresh_rotation=*/false, /*horizontal=*/horizontal_);
    });
    return true;  // solve() synchronises
  }

  bool keep(KeptSystem& slot) override {
    if (!factored_exact_ || kept_) return false;
    // The factor and, with the rotation freed, its rotation frame (linearize's u and
    // tmp = [a; |u|²]): one launch.
    kernels::CopyList copies;
    copies.entry[0] = {S_.Hr.get(), S_.Hk.get(), sz(m_) * sz(m_)};
    int entries = 1;
    if (horizontal_) {
      const size_t n4 = 4 * sz(c_.n_);
      copies.entry[1] = {S_.Ta.get() + n4 * sz(S_.dim), S_.ku.get(), n4};
      copies.entry[2] = {S_.Tca.get() + n4 * sz(S_.dim), S_.kuc.get(), n4};
      copies.entry[3] = {S_.tmp.get(), S_.ka.get(), sz(m_)};
      entries = 4;
    }
    HSI_CUDA_CHECK(kernels::copy(copies, entries, st()));
    S_.kept_order = m_;
    S_.kept_diagonal_max = diagonal_max_;
    slot.owner = &S_;
    slot.generation = ++S_.kept_count;
    slot.data.reset();
    slot.order = m_;
    slot.free_rotation = rotation_;
    slot.modulo_rotation = horizontal_;
    factored_exact_ = false;
    return true;
  }

  NewtonSystem solve(double ridge) override { return run_solve(ridge, false); }

  // Split where the triangular solves are our cluster kernel, which runs the forward
  // substitution alone (dense_cholesky.h); elsewhere solve() itself.
  NewtonSystem decrement(double ridge) override {
    return run_solve(ridge, S_.split_solve && !kept_ && own_solve());
  }

  NewtonSystem direction() override {
    if (!pending_.factored || pending_.has_direction) throw std::logic_error("hsi::cuda: direction() without a split decrement()");
    const std::uint64_t shape = std::uint64_t{rotation_} | std::uint64_t{horizontal_} << 1 | std::uint64_t{quad_ != nullptr} << 2;
    S_.graphs.run(key(kDirection, shape), st(), [&] {
      HSI_CUDA_CHECK(kernels::cholesky_solve(m_, S_.Hr.get(), m_, S_.d.get(), st(), kernels::Substitution::Back));
      enqueue_direction();
    });
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    NewtonSystem sys = pending_;
    pending_.has_direction = true;
    sys.has_direction = true;
    read_direction(sys);
    return sys;
  }

  void trial_energies(std::span<const double> steps, std::span<double> energies) override {
    for (size_t begin = 0; begin < steps.size(); begin += kBatch) {
      const int count = static_cast<int>(std::min<size_t>(kBatch, steps.size() - begin));
      write_params(kSteps, [&] { std::copy_n(steps.begin() + static_cast<std::ptrdiff_t>(begin), count, S_.params.get() + param(kSteps)); });
      S_.graphs.run(key(kTrialEnergies, static_cast<std::uint64_t>(count)), st(), [&] {
        copy_params(kSteps, count);
        HSI_CUDA_CHECK(kernels::mean_energies(c_.G_, c_.g_.get(), c_.ab_.get(), c_.dab_.get(), S_.sc.get() + kSteps, count,
                                              c_.part_sum_.get(), c_.part_bad_.get(), c_.done_.get(), down(kTrials), st()));
      });
      params_read(kSteps);
      HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
      for (int j = 0; j < count; ++j) {
        const double s = steps[begin + sz(j)];
        energies[begin + sz(j)] = S_.sc_down[kTrials + j] + (quad_ ? q0_ + s * q1_ + 0.5 * s * s * q2_ : 0.0);
      }
    }
  }

  // Enqueued now, fetched by the certify(step, false) that follows (NewtonStepper::
  // certify_ahead): the trial energies the loop asks for next wait for both.
  void certify_ahead(double step) override {
    if (!certify_ || step == 0) return;
    enqueue_certificate(step, false);
    ahead_step_ = step;
  }

  CertificateResult certify(double step, bool full) override {
    if (!certify_) throw InputError("hsi::cuda: no certifier to certify with");
    const bool ahead = !full && step == ahead_step_;
    ahead_step_ = std::numeric_limits<double>::quiet_NaN();
    if (!ahead) enqueue_certificate(step, full);
    return c_.certifier_->fetch();
  }

  void enqueue_certificate(double step, bool full) {
    const bool trial = step != 0;
    if (trial) write_params(kStep, [&] { S_.params[param(kStep)] = step; });
    const std::uint64_t shape = std::uint64_t{trial} | std::uint64_t{full} << 1 | std::uint64_t{rotation_} << 2;
    S_.graphs.run(key(kCertify, shape), st(), [&] {
      const double* x = S_.xa.get();
      if (trial) {
        enqueue_trial();
        x = S_.xna.get();
      }
      // Full coefficients of x into S.full (X0 + X x), then the certificate.
      kernels::TallOptions expand;
      expand.y0 = S_.X0.get();
      HSI_CUDA_CHECK(kernels::tall_times_one(S_.M4, S_.dim, S_.X.get(), x, S_.full.get(), st(), expand));
      CertificateOptions o;
      o.stop_at_first_failure = !full;
      c_.certifier_->enqueue(reinterpret_cast<const double2*>(S_.full.get()), o);
    });
    if (trial) {
      params_read(kStep);
      trial_step_ = step;
    }
  }

  void accept(double step) override {
    // x ← the very point certify() looked at, else one made alike; copied (not swapped),
    // since the graphs keep the buffers' addresses.
    const bool trial = !(step == trial_step_);
    ahead_step_ = std::numeric_limits<double>::quiet_NaN();
    if (trial) write_params(kStep, [&] { S_.params[param(kStep)] = step; });
    S_.graphs.run(key(kAccept, std::uint64_t{trial} | std::uint64_t{rotation_} << 1), st(), [&] {
      if (trial) enqueue_trial();
      set_coefficients(S_.xna.get());  // and x ← xna
    });
    if (trial) params_read(kStep);
    trial_step_ = std::numeric_limits<double>::quiet_NaN();
    x_down_valid_ = false;
  }

  Eigen::VectorXd x() override {
    const int dim = S_.dim;
    // A solve since x last moved copied it down: a solve that ends on its decrement
    // (newton_run's usual last call) needs no wait of its own for x.
    if (x_down_valid_) return Eigen::Map<const Eigen::VectorXd>(S_.x_down.get(), dim);
    HSI_CUDA_CHECK(cudaMemcpyAsync(S_.x_up.get(), S_.xa.get(), sz(dim) * sizeof(double), cudaMemcpyDeviceToHost, st()));
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    return Eigen::Map<const Eigen::VectorXd>(S_.x_up.get(), dim);
  }

 private:
  cudaStream_t st() const { return c_.stream_; }
  // A scalar slot's pinned host copy, written by the kernels themselves (pinned memory is
  // mapped into the device's address space at the same address under unified
  // addressing): no copy node per call; read after the call's synchronisation.
  double* down(Slot s) const { return S_.sc_down.get() + s; }

  // The pinned parameter slots are written only once the graph that last copied from
  // them has run past that copy, tracked per group of slots (DeviceSpace::params_done):
  // the ridge, the step, the trial steps.
  static int group(Slot s) { return s == kRidge ? 0 : s == kStep ? 1 : 2; }
  template <class Fill>
  void write_params(Slot slot, Fill&& fill) {
    const int g = group(slot);
    if (S_.params_pending[g]) HSI_CUDA_CHECK(cudaEventSynchronize(S_.params_done[g]));
    S_.params_pending[g] = false;
    fill();
  }
  void params_read(Slot slot) {
    const int g = group(slot);
    HSI_CUDA_CHECK(cudaEventRecord(S_.params_done[g], st()));
    S_.params_pending[g] = true;
  }
  // Inside a graph: the parameter slots [first, first + count) into sc.
  void copy_params(Slot first, int count) {
    HSI_CUDA_CHECK(cudaMemcpyAsync(S_.sc.get() + first, S_.params.get() + param(first), sz(count) * sizeof(double),
                                   cudaMemcpyHostToDevice, st()));
  }

  void enqueue_linearize(const HessianChoice& choice) {
    enqueue_gradient();
    // Hessian: Hv (4n × 4n) as CudaNewtonCore::hessian(), then Hr = Taᵀ Hv Ta (+ Q).
    c_.build_hessian(choice.projection, choice.exact, choice.all_samples);
    enqueue_hessian_rest();
  }

  // The gradient g at x (m_ entries; with the rotation freed and fresh_rotation, u = R T x
  // first, else the u already in Ta and Tca); with `horizontal`, its horizontal part
  // (g_T −= (g_dim/|u|²) a with a = tmp, then g_dim = 0; the kept system's frame).
  void enqueue_gradient(bool fresh_rotation = true, bool horizontal = false) {
    const int n = c_.n_, dim = S_.dim;
    if (rotation_ && fresh_rotation) {  // u = R T x in both layouts, as the last columns of Ta and Tca: one launch
      kernels::TallOptions o;
      o.second_A = S_.RTc.get();
      o.second_rows = 4 * n;
      o.second_y = S_.Tca.get() + sz(4 * n) * sz(dim);
      HSI_CUDA_CHECK(kernels::tall_times_one(4 * n, dim, S_.RT.get(), S_.xa.get(), S_.Ta.get() + sz(4 * n) * sz(dim), st(), o));
    }
    // Gradient: [gφ | gψ] = Dᴴ [ga | gb], then g = Tcaᵀ (·) / |G| in the same launch (+ Q x + c).
    HSI_CUDA_CHECK(kernels::gradient_samples(c_.G_, c_.g_.get(), c_.ab_.get(), c_.gab_.get(), st()));
    kernels::ReducedGradient then;
    then.T = S_.Tca.get();
    then.m = m_;
    then.scale = 1 / static_cast<double>(c_.G_);
    then.g = S_.g.get();
    then.a = horizontal ? S_.tmp.get() : nullptr;
    then.dim = dim;
    then.done = c_.done_.get();
    HSI_CUDA_CHECK(kernels::tall_adjoint_times_two(c_.G_, n, c_.D_, c_.gab_.get(), c_.coef_.get(), st(), then));
    if (quad_) {
      HSI_CUDA_CHECK(cublasDgemv(c_.blas_, CUBLAS_OP_N, dim, dim, &kOneD, S_.Q.get(), dim, S_.xa.get(), 1, &kOneD, S_.g.get(), 1));
      HSI_CUDA_CHECK(cublasDaxpy(c_.blas_, dim, &kOneD, S_.c.get(), 1, S_.g.get(), 1));
    }
  }

  // The rest of linearize: the Hessian and the reduced system.
  void enqueue_hessian_rest() {
    const int n = c_.n_, dim = S_.dim;
    HSI_CUDA_CHECK(cublasDgemm(c_.blas_, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n, m_, 4 * n, &kOneD, c_.Hv_.get(), 4 * n, S_.Ta.get(),
                               4 * n, &kZeroD, S_.Y.get(), 4 * n));
    HSI_CUDA_CHECK(cublasDgemm(c_.blas_, CUBLAS_OP_T, CUBLAS_OP_N, m_, m_, 4 * n, &kOneD, S_.Ta.get(), 4 * n, S_.Y.get(), 4 * n,
                               &kZeroD, S_.Hr0.get(), m_));
    if (quad_)  // m_ = dim here: the quadratic term never frees the rotation
      HSI_CUDA_CHECK(cublasDgeam(c_.blas_, CUBLAS_OP_N, CUBLAS_OP_N, dim, dim, &kOneD, S_.Hr0.get(), dim, &kOneD, S_.Q.get(), dim,
                                 S_.Hr0.get(), dim));
    if (horizontal_) {
      // The exact system modulo the rotation (HessianChoice::free_rotation, newton.h): with
      // a = Tᵀu (tmp), k = Tᵀ Hv u (column dim of Hr0), c = uᵀ Hv u, the system in d is
      // K_TT − (a kᵀ + k aᵀ)/|u|² + c a aᵀ/|u|⁴ and the gradient g_T − (uᵀg/|u|²) a; row and
      // column dim are cleared (their diagonal set to max|diag| below), so the (dim+1)
      // system solves the dim one with d[dim] = 0, and solve() sets θ = −aᵀd/|u|².
      HSI_CUDA_CHECK(cublasDgemv(c_.blas_, CUBLAS_OP_T, 4 * n, m_, &kOneD, S_.Ta.get(), 4 * n, S_.Ta.get() + sz(4 * n) * sz(dim), 1,
                                 &kZeroD, S_.tmp.get(), 1));
      // (and max |diag| into sc's kDiagMax, for the solve's ridge, and the cleared diagonal entry)
      HSI_CUDA_CHECK(kernels::horizontal_system(dim, S_.Hr0.get(), S_.tmp.get(), S_.g.get(), S_.sc.get() + kDiagMax, st()));
    } else {
      HSI_CUDA_CHECK(kernels::diag_abs_max(m_, S_.Hr0.get(), S_.sc.get() + kDiagMax, st()));
    }
  }

  // Whether the triangular solves are dense_cholesky.h's cluster kernel (not cuSOLVER's
  // potrs): it also runs either substitution alone, which decrement() needs.
  bool own_solve() const { return !S_.cusolver_solve && kernels::cholesky_solve_in_cluster(m_); }

  // solve(), or with `split` decrement(): the factor and the forward substitution alone.
  NewtonSystem run_solve(double ridge, bool split) {
    factored_exact_ = false;
    own_factor_ = !kept_ && S_.own_cholesky && m_ <= kernels::kCholeskyPreferredMaxOrder;
    if (!kept_) write_params(kRidge, [&] { S_.params[param(kRidge)] = ridge; });
    const std::uint64_t shape = std::uint64_t{rotation_} | std::uint64_t{horizontal_} << 1 | std::uint64_t{quad_ != nullptr} << 2 |
                                std::uint64_t{kept_} << 3 | std::uint64_t{split} << 4;
    S_.graphs.run(key(kSolve, shape), st(), [&] { enqueue_solve(split); });
    if (!kept_) params_read(kRidge);
    HSI_CUDA_CHECK(cudaStreamSynchronize(st()));
    // A new direction: no trial point or certificate asked ahead is along it.
    trial_step_ = ahead_step_ = std::numeric_limits<double>::quiet_NaN();
    x_down_valid_ = true;
    start_pending_ = false;  // (the start's graph ran before this one)
    NewtonSystem sys;
    sys.diagonal_max = kept_ ? S_.kept_diagonal_max : S_.sc_down[kDiagMax];
    if (!kept_) diagonal_max_ = sys.diagonal_max;
    sys.gradient_norm = std::sqrt(S_.sc_down[kGradNorm2]);
    sys.slope = S_.sc_down[kSlope];
    // The factorisation's and the solve's own status: potrs after a failed potrf reads
    // an unfinished factor, whose numbers may well be finite.
    int info[2];
    std::memcpy(info, S_.sc_down.get() + kInfo, sizeof info);
    sys.factored = info[0] == 0 && info[1] == 0 && std::isfinite(sys.slope);
    factored_exact_ = sys.factored && exact_ && !kept_;
    if (split) {
      sys.max_safe_step = std::numeric_limits<double>::quiet_NaN();
      sys.has_direction = false;
    } else {
      read_direction(sys);
    }
    pending_ = sys;
    return sys;
  }

  // A system's direction scalars once its direction is made (solve(), direction()).
  void read_direction(NewtonSystem& sys) {
    sys.slope = S_.sc_down[kSlope];
    sys.max_safe_step = S_.sc_down[kSafeStep];
    sys.factored = sys.factored && std::isfinite(sys.slope);
    if (quad_) {
      q0_ = 0.5 * S_.sc_down[kQuad0] + S_.sc_down[kScratch] + quad_->k;
      q1_ = S_.sc_down[kQuad1];
      q2_ = S_.sc_down[kQuad2];
    }
  }

  // With `split` (decrement()): the factor and y = −L⁻¹g in d, then the decrement
  // −‖y‖² as the slope; direction() does the rest.
  void enqueue_solve(bool split) {
    const int dim = S_.dim, m = m_;
    {  // x into x_down (mapped pinned memory), for x() (x_down_valid_)
      kernels::CopyList copies;
      copies.entry[0] = {S_.xa.get(), S_.x_down.get(), sz(dim)};
      HSI_CUDA_CHECK(kernels::copy(copies, 1, st()));
    }
    if (!kept_) {
      copy_params(kRidge, 1);
      HSI_CUDA_CHECK(kernels::add_relative_ridge(m, S_.Hr0.get(), S_.sc.get() + kRidge, S_.sc.get() + kDiagMax, down(kDiagMax),
                                                 S_.Hr.get(), st()));
    }
    // d = −g, solved in place: cuSOLVER's Cholesky, or with HSI_CUDA_CHOLESKY=own ours
    // (dense_cholesky.h) up to its preferred order.
    const bool own = own_factor_;
    int* info = reinterpret_cast<int*>(S_.sc.get() + kInfo);  // [factor, solves], copied down with the scalars
    HSI_CUDA_CHECK(kernels::negate(m, S_.g.get(), S_.d.get(), info, st()));  // and both statuses 0
    // The triangular solves with a factor L (the kept one or potrf's): dense_cholesky.h's
    // cluster kernel where it applies (forward and back substitution in one kernel: 31.6
    // against potrs' 56.5 µs at m = 292 on an H200, bench_dense), else cuSOLVER's potrs.
    auto triangular_solves = [&](const double* L) {
      if (split) {  // (decrement() splits only where own_solve() holds)
        HSI_CUDA_CHECK(kernels::cholesky_solve(m, L, m, S_.d.get(), st(), kernels::Substitution::Forward));
      } else if (own_solve()) {
        HSI_CUDA_CHECK(kernels::cholesky_solve(m, L, m, S_.d.get(), st()));  // no status of its own: info[1] stays 0
      } else {
        HSI_CUDA_CHECK(cusolverDnDpotrs(c_.solver_, CUBLAS_FILL_MODE_LOWER, m, 1, L, m, S_.d.get(), m, info + 1));
      }
    };
    if (kept_) {  // the kept factor (keep): the triangular solves only (info[0] stays 0)
      triangular_solves(S_.Hk.get());
    } else if (own) {  // our factor (L in the lower triangle, as potrf leaves it: keep() may copy it)
      HSI_CUDA_CHECK(kernels::cholesky_factor(m, S_.Hr.get(), m, info, st()));
      triangular_solves(S_.Hr.get());
    } else {
      HSI_CUDA_CHECK(cusolverDnDpotrf(c_.solver_, CUBLAS_FILL_MODE_LOWER, m, S_.Hr.get(), m, S_.work.get(), S_.lwork, info));
      triangular_solves(S_.Hr.get());
    }
    if (split) {
      HSI_CUDA_CHECK(kernels::decrement_scalars(dim, m, S_.g.get(), S_.d.get(), down(kSlope), down(kGradNorm2), info,
                                                reinterpret_cast<int*>(down(kInfo)), st()));
      return;
    }
    enqueue_direction(info);
  }

  // After the triangular solves: with the system modulo the rotation θ = −aᵀd / |u|²
  // into d[dim] (0 from the decoupled solve); then the slope gᵀd and |g|² (one launch;
  // with `info`, the statuses copied down too), the quadratic term along d, d in the
  // samples and the safe step along it.
  void enqueue_direction(const int* info = nullptr) {
    const int n = c_.n_, dim = S_.dim, m = m_;
    HSI_CUDA_CHECK(kernels::step_scalars(dim, m, horizontal_, S_.tmp.get(), S_.g.get(), S_.d.get(), down(kSlope), down(kGradNorm2),
                                         info, info ? reinterpret_cast<int*>(down(kInfo)) : nullptr, st()));
    if (quad_) {  // the quadratic term along d: q(x + s d) = q0 + s q1 + ½ s² q2
      HSI_CUDA_CHECK(cublasDgemv(c_.blas_, CUBLAS_OP_N, dim, dim, &kOneD, S_.Q.get(), dim, S_.xa.get(), 1, &kZeroD, S_.tmp.get(), 1));
      HSI_CUDA_CHECK(kernels::dot(dim, S_.xa.get(), S_.tmp.get(), down(kQuad0), st()));
      HSI_CUDA_CHECK(kernels::dot(dim, S_.c.get(), S_.xa.get(), down(kScratch), st()));
      HSI_CUDA_CHECK(cublasDaxpy(c_.blas_, dim, &kOneD, S_.c.get(), 1, S_.tmp.get(), 1));
      HSI_CUDA_CHECK(kernels::dot(dim, S_.tmp.get(), S_.d.get(), down(kQuad1), st()));
      HSI_CUDA_CHECK(cublasDgemv(c_.blas_, CUBLAS_OP_N, dim, dim, &kOneD, S_.Q.get(), dim, S_.d.get(), 1, &kZeroD, S_.tmp.get(), 1));
      HSI_CUDA_CHECK(kernels::dot(dim, S_.d.get(), S_.tmp.get(), down(kQuad2), st()));
    }
    // Direction in the samples, [dφ | dψ] = Tca d, and the largest safe step along it.
    HSI_CUDA_CHECK(cublasDgemv(c_.blas_, CUBLAS_OP_N, 4 * n, m, &kOneD, S_.Tca.get(), 4 * n, S_.d.get(), 1, &kZeroD,
                               reinterpret_cast<double*>(c_.coef_.get()), 1));
    HSI_CUDA_CHECK(kernels::tall_times_two(c_.G_, n, c_.D_, c_.coef_.get(), c_.dab_.get(), st()));
    HSI_CUDA_CHECK(kernels::max_safe_step(c_.G_, c_.ab_.get(), c_.dab_.get(), c_.part_sum_.get(), c_.done_.get(),
                                          down(kSafeStep), st()));
  }

  // ab = D · (Tc x) at the device's current x; with `from`, x ← from first (the same
  // launch as Tc x).
  void set_coefficients(const double* from = nullptr) {
    kernels::TallOptions o;
    o.x_copy = from ? S_.xa.get() : nullptr;
    HSI_CUDA_CHECK(kernels::tall_times_one(4 * c_.n_, S_.dim, S_.Tca.get(), from ? from : S_.xa.get(),
                                           reinterpret_cast<double*>(c_.coef_.get()), st(), o));
    HSI_CUDA_CHECK(kernels::tall_times_two(c_.G_, c_.n_, c_.D_, c_.coef_.get(), c_.ab_.get(), st()));
  }

  // Inside a graph: xna = x ⊕ s·d with s the step slot: x + s d, or regauge(Ta ([x; 0] +
  // s d)) with the rotation freed.
  void enqueue_trial() {
    const int dim = S_.dim;
    copy_params(kStep, 1);
    if (!rotation_) {
      HSI_CUDA_CHECK(kernels::trial_point(dim, S_.xa.get(), S_.d.get(), S_.sc.get() + kStep, S_.xna.get(), st()));
    } else {
      const int n = c_.n_, m = dim + 1;
      kernels::TallOptions o;  // v = Ta ([x; 0] + s d), the point formed in the same launch
      o.dx = S_.d.get();
      o.step = S_.sc.get() + kStep;
      HSI_CUDA_CHECK(kernels::tall_times_one(4 * n, m, S_.Ta.get(), S_.xa.get(), S_.v.get(), st(), o));
      HSI_CUDA_CHECK(kernels::regauge(dim, n, S_.rotation_vertex, S_.primary.get(), S_.v.get(), S_.xna.get(), st()));
    }
  }

  static constexpr double kOneD = 1, kZeroD = 0;
  CudaNewtonCore& c_;
  DeviceSpace& S_;
  const QuadraticTerm* quad_;
  bool certify_;
  int m_ = 0;
  bool rotation_ = false;
  bool horizontal_ = false;  // the exact system modulo the rotation (linearize)
  bool kept_ = false;            // linearize_kept: solve() solves with the kept factor S_.Hk
  bool exact_ = false;           // the last linearize() built the exact Hessian
  bool factored_exact_ = false;  // the last solve() factored it (keep() may copy S_.Hr)
  bool own_factor_ = false;      // … with dense_cholesky.h's kernel
  double diagonal_max_ = 0;      // max |diag| of the last system solve() factored (its ridge kernel's copy)
  bool x_down_valid_ = false;    // S_.x_down holds x (a solve's graph copied it since x last moved)
  bool start_pending_ = false;   // start_deferred's graph not yet waited for (start_energy)
  double start_quad_ = 0;        // the quadratic term at the start
  double ahead_step_ = std::numeric_limits<double>::quiet_NaN();  // certify_ahead's step (NaN: none)
  NewtonSystem pending_;         // the last solve's system (decrement(): direction() finishes it)
  double trial_step_ = std::numeric_limits<double>::quiet_NaN();  // the step xna holds
  double q0_ = 0, q1_ = 0, q2_ = 0;
};

void CudaNewtonCore::warm_up() {
  // The per-call interface (the host stepper's path), at zero coefficients: a = b = 0 and
  // a zero direction afterwards, as before.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(4 * static_cast<Eigen::Index>(n_));
  set_coefficients(zero);
  (void)energy();
  (void)gradient();
  (void)hessian(HessianProjection::PartProj, false, false);
  set_direction(zero);
  (void)max_safe_step();
  (void)energy_at(0.5);
  if (!setup_) return;
  // The device stepper in both spaces of the setup, from the identity map: the
  // interpolation's space with the rotation freed and not, exact and projected Hessians,
  // trial energies, both certificates and a trial step accepted; the authoring space with
  // a quadratic term (its extra products).
  const HarmonicMap identity = identity_map(setup_->cage);
  constexpr double kSteps[kBatch] = {1, 0.5, 0.25, 0.125};
  double energies[kBatch];
  auto iterate = [&](DeviceStepper& st, const MapSpace& space, bool free_rotation) {
    const Eigen::VectorXd x0 = space.reduce(identity).x;
    (void)st.start(x0);
    HessianChoice exact;
    exact.exact = true;
    exact.free_rotation = free_rotation;  // the interpolation's exact system modulo the rotation
    // A ridge that keeps every system definite (the freed rotation is a null direction
    // at the identity): the direction stays finite, so every later call sees numbers.
    st.linearize(exact);
    const double ridge = 1e-3;  // (relative to max |diag H|: NewtonStepper::solve)
    (void)st.solve(ridge);
    // The same system as newton_run asks for an exact one: the decrement, then the direction.
    const NewtonSystem decrement = st.decrement(ridge);
    if (decrement.factored && !decrement.has_direction) (void)st.direction();
    KeptSystem kept;  // chord steps' calls (NewtonOptions::kept_system)
    if (st.keep(kept) && st.linearize_kept(kept)) (void)st.solve(0);
    HessianChoice projected;
    projected.free_rotation = free_rotation;
    st.linearize(projected);
    (void)st.solve(ridge);
    st.trial_energies(kSteps, energies);
    (void)st.certify(0, true);
    (void)st.certify(kSteps[3], false);
    st.accept(kSteps[3]);
    (void)st.x();
  };
  // Twice: the first runs each call directly (loading what it uses), the second
  // captures its graph (GraphCache), so that neither falls on the first frames.
  for (int pass = 0; pass < 2; ++pass) {
    DeviceStepper st(*this, device_space(setup_->metric_space), nullptr, true);
    iterate(st, setup_->metric_space, true);
  }
  {
    QuadraticTerm quad;
    const Eigen::Index dim = setup_->map_space.dim();
    quad.Q = Eigen::MatrixXd::Identity(dim, dim);
    quad.c = Eigen::VectorXd::Zero(dim);
    for (int pass = 0; pass < 2; ++pass) {
      DeviceStepper st(*this, device_space(setup_->map_space), &quad, true);
      iterate(st, setup_->map_space, false);
    }
  }
  // Back to the documented initial state.
  set_coefficients(zero);
  set_direction(zero);
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

std::unique_ptr<NewtonStepper> CudaNewtonCore::make_stepper(const MapSpace& space, const Certifier* certifier,
                                                            const QuadraticTerm* quad) {
  // Only for the setup this core was made with: its certifier is the one on the device.
  if (!setup_ || (certifier && certifier != &setup_->certifier)) return nullptr;
  if (&space != &setup_->map_space && &space != &setup_->metric_space) return nullptr;
  return std::make_unique<DeviceStepper>(*this, device_space(space), quad, certifier != nullptr);
}

}  // namespace hsi::cuda
