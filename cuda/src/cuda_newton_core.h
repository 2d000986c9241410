// CudaNewtonCore: the GPU twin of engine/src/newton.cpp's CpuNewtonCore (declared
// here so that its parts live in two files: newton_core.cpp, the per-call NewtonCore
// interface, and device_newton.cpp, the whole certified iteration on the device).
// Sample data (D at G, the subset H, target metrics, a = Dφ, b = Dψ and the direction)
// stay on the device; per-sample work is newton_kernels.cu (sample_math.cuh), the
// products with D are cuBLAS, factorisation is cuSOLVER. Host code only (compiled by
// the C++ compiler, Eigen on this side), one stream.
#pragma once

#include <algorithm>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "device_certifier.h"
#include "device.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/domain.h"
#include "hsi/shape_setup.h"
#include "newton_kernels.h"

namespace hsi::cuda {


inline sample::Projection to_device(HessianProjection p) {
  switch (p) {
    case HessianProjection::Delete: return sample::Projection::Delete;
    case HessianProjection::FullProj: return sample::Projection::FullProj;
    case HessianProjection::PartProj: return sample::Projection::PartProj;
  }
  throw InputError("hsi::cuda: unknown Hessian projection");
}

inline size_t sz(int v) { return static_cast<size_t>(v); }

// The reduced space's matrices and the device loop's buffers (one per MapSpace the
// core has solved in).
class DeviceStepper;

// Vectors of the reduced space have room for one more unknown, the freed rotation θ
// (HessianChoice::free_rotation): m = dim + 1.
struct DeviceSpace {
  int dim = 0, n4 = 0, M4 = 0, rotation_vertex = 0;
  DeviceArray<double> Ta;   // 4n × m, v layout (Re φ, Im φ, Re ψ, Im ψ): [T | u], the Hessian's
  DeviceArray<double> Tca;  // 4n × m, rows in complex order: Tc x = [φ_a | ψ_a] as double2, then u
  DeviceArray<double> RT, RTc;  // the rotation generator times T and Tc: u = RT x
  DeviceArray<double> X;    // 4M × dim: the full coefficients [φ | ψ] (double2) per unit x
  DeviceArray<double> X0;   // 4M: expand(0)
  DeviceArray<int> primary; // MapSpace::primary_rows
  DeviceArray<double> xa, xna, g, d, tmp, v, Hr, Hr0, Y, work, full, Q, c;  // xa = [x; 0], xna the trial
  DeviceArray<double> sc;     // the stepper's scalar slots (device_newton.cpp)
  PinnedArray<double> sc_down;
  PinnedArray<double> x_up;
  PinnedArray<double> x_down;  // x as the last solve's graph left it (DeviceStepper::x without a wait)
  PinnedArray<double> params;  // per-call numbers (ridge, steps) the graphs copy into sc
  // Per group of parameter slots (the ridge; the step; the trial steps): recorded after
  // the last graph that copied from that group, so that filling one group never waits
  // for a graph that reads another (a certificate asked ahead, then trial energies).
  Event params_done[3];
  bool params_pending[3] = {false, false, false};
  GraphCache graphs{graphs_enabled()};  // the stepper's calls, one graph per call shape
  bool own_cholesky = own_cholesky_enabled();  // dense_cholesky.h instead of cuSOLVER (device_newton.cpp, solve)
  bool cusolver_solve = cusolver_solve_forced();  // potrs instead of dense_cholesky.h's cholesky_solve
  bool split_solve = split_solve_enabled();  // decrement() splits the exact system's solve (device_newton.cpp)
  int lwork = 0;
  // A factor kept for chord steps (NewtonStepper::keep): cuSOLVER's lower factor, order
  // kept_order; kept_count counts the keeps, a KeptSystem's generation names its own.
  DeviceArray<double> Hk;
  DeviceArray<double> ku, kuc, ka;  // its rotation frame: u (v layout, complex order) and a = Tᵀu, |u|²
  std::uint64_t kept_count = 0;
  int kept_order = 0;
  double kept_diagonal_max = 0;
};

// D at G, the subset H and D's rows at H on one device: read only once uploaded, so the
// cores made for one ShapeSetup on one GPU share one copy (ShapeSetup::shared_backend_data).
struct SampleRows {
  DeviceArray<double2> D;   // G × n, column-major (as Eigen stores it)
  DeviceArray<double2> DH;  // the rows H of D, |H| × n
  DeviceArray<int> H;       // indices into G
  // Uploaded on `stream`, which is synchronised before it returns (D and H are the
  // caller's pageable memory, and other streams read the copy).
  static std::shared_ptr<SampleRows> upload(const MatrixXcd& D, const std::vector<int>& H, cudaStream_t stream) {
    auto r = std::make_shared<SampleRows>();
    const int G = static_cast<int>(D.rows()), n = static_cast<int>(D.cols()), h = static_cast<int>(H.size());
    r->D = DeviceArray<double2>(sz(G) * sz(n));
    r->DH = DeviceArray<double2>(sz(h) * sz(n));
    r->H = DeviceArray<int>(sz(h));
    static_assert(sizeof(cd) == sizeof(double2), "std::complex<double> and double2 share a layout");
    HSI_CUDA_CHECK(cudaMemcpyAsync(r->D.get(), D.data(), r->D.bytes(), cudaMemcpyHostToDevice, stream));
    HSI_CUDA_CHECK(cudaMemcpyAsync(r->H.get(), H.data(), r->H.bytes(), cudaMemcpyHostToDevice, stream));
    HSI_CUDA_CHECK(kernels::gather_rows(G, h, n, r->D.get(), r->H.get(), r->DH.get(), stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    return r;
  }
};

class CudaNewtonCore final : public NewtonCore {
 public:
  // With a setup, the core can also run whole solves on the device (solve()) for that
  // setup's spaces and certifier; the setup must outlive the core.
  CudaNewtonCore(const MatrixXcd& D, const std::vector<int>& H, const ShapeSetup* setup = nullptr)
      : G_(static_cast<int>(D.rows())),
        n_(static_cast<int>(D.cols())),
        h_(static_cast<int>(H.size())),
        blas_(stream_),
        g_(3 * sz(G_)),
        ab_(2 * sz(G_)),
        dab_(2 * sz(G_)),
        gab_(2 * sz(G_)),
        coef_(2 * sz(n_)),
        W_(6 * sz(h_)),
        Wt_(sz(h_) * 6 * sz(n_)),
        R_(sz(n_) * 6 * sz(n_)),
        Hv_(16 * sz(n_) * sz(n_)),
        part_sum_(sz(kernels::kMaxPartials) * sz(kernels::kMaxSteps)),
        part_bad_(sz(kernels::kMaxPartials) * sz(kernels::kMaxSteps)),
        done_(1),
        scalar_(1),
        targets_up_(3 * sz(G_)),
        coef_up_(2 * sz(n_)),
        scalar_down_(1),
        coef_down_(2 * sz(n_)) {
    const cudaStream_t s = stream_;
    // D at G and H: one copy per setup and GPU, shared by its cores (the first one made
    // uploads it); without a setup this core's own.
    if (setup && &D == &setup->D_G && &H == &setup->H)
      rows_ = std::static_pointer_cast<const SampleRows>(
          setup->shared_backend_data(device_key("sample rows"), [&] { return SampleRows::upload(D, H, s); }));
    else
      rows_ = SampleRows::upload(D, H, s);
    D_ = rows_->D.get();
    DH_ = rows_->DH.get();
    H_ = rows_->H.get();
    // Nothing is ever read uninitialised: a = b = 0 (every sample degenerate, E = +inf)
    // and a zero direction until set; identity targets, as on the CPU.
    HSI_CUDA_CHECK(cudaMemsetAsync(ab_.get(), 0, ab_.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(dab_.get(), 0, dab_.bytes(), s));
    HSI_CUDA_CHECK(cudaMemsetAsync(done_.get(), 0, done_.bytes(), s));  // the one-launch reductions' counter
    double* g = targets_up_.begin_fill();
    for (size_t i = 0; i < sz(G_); ++i) {
      g[3 * i] = 1;
      g[3 * i + 1] = 0;
      g[3 * i + 2] = 1;
    }
    targets_up_.send(g_.get(), g_.size(), s);
    HSI_CUDA_CHECK(cudaStreamSynchronize(s));
    if (setup) {
      setup_ = setup;
      certifier_ = std::make_unique<DeviceCertifier>(*setup, stream_, blas_);  // its rows, not evaluated again (one copy per GPU)
    }
    warm_up();
  }

  // Nothing may be in flight while the members free their memory.
  ~CudaNewtonCore() override;  // device_newton.cpp (DeviceSpace is complete there)

  int n() const override { return n_; }
  const char* name() const override { return "cuda"; }
  ExactSamples preferred_exact_samples() const override { return ExactSamples::All; }

  void set_targets(const std::vector<Metric>& g) override {
    if (g.size() != sz(G_)) throw InputError("target metrics do not match the samples");
    double* out = targets_up_.begin_fill();
    for (size_t i = 0; i < g.size(); ++i) {
      out[3 * i] = g[i](0);
      out[3 * i + 1] = g[i](1);
      out[3 * i + 2] = g[i](2);
    }
    targets_up_.send(g_.get(), g_.size(), stream_);
  }

  // The sets stay on the device; per frame only the weights are uploaded.
  std::uint64_t set_target_keys(std::vector<std::vector<Metric>> keys, std::vector<std::vector<Metric>> log_keys) override {
    auto upload = [&](const std::vector<std::vector<Metric>>& sets, DeviceArray<double>& dst) {
      for (const auto& set : sets)
        if (set.size() != sz(G_)) throw InputError("target metric sets do not match the samples");
      std::vector<double> flat(sets.size() * 3 * sz(G_));
      for (size_t j = 0; j < sets.size(); ++j)
        for (size_t i = 0; i < sz(G_); ++i)
          for (int q = 0; q < 3; ++q) flat[(j * sz(G_) + i) * 3 + sz(q)] = sets[j][i](q);
      dst = DeviceArray<double>(flat.size());
      if (!flat.empty()) HSI_CUDA_CHECK(cudaMemcpyAsync(dst.get(), flat.data(), dst.bytes(), cudaMemcpyHostToDevice, stream_));
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));  // flat is pageable
    };
    upload(keys, keys_);
    upload(log_keys, log_keys_);
    key_count_ = static_cast<int>(keys.size());
    log_key_count_ = static_cast<int>(log_keys.size());
    weights_up_ = std::make_unique<Upload<double>>(std::max<size_t>(1, std::max(keys.size(), log_keys.size())));
    weights_ = DeviceArray<double>(std::max<size_t>(1, std::max(keys.size(), log_keys.size())));
    return target_token_ = next_target_token();
  }
  bool blend_targets(std::uint64_t token, std::span<const double> w, bool exponential) override {
    if (token == 0 || token != target_token_) return false;  // 0: no sets given yet
    const int K = exponential ? log_key_count_ : key_count_;
    if (static_cast<int>(w.size()) != K)
      throw InputError("blend_targets: " + std::to_string(w.size()) + " weights for " + std::to_string(K) + " metric sets");
    double* up = weights_up_->begin_fill();
    std::copy(w.begin(), w.end(), up);
    weights_up_->send(weights_.get(), w.size(), stream_);
    HSI_CUDA_CHECK(kernels::blend_metrics(G_, K, (exponential ? log_keys_ : keys_).get(), weights_.get(), exponential, g_.get(), stream_));
    return true;
  }

  void set_coefficients(const Eigen::VectorXd& v) override { apply_D(v, ab_.get(), "coefficient"); }
  void set_direction(const Eigen::VectorXd& dv) override { apply_D(dv, dab_.get(), "direction"); }

  double energy() override { return mean_energy(0.0); }
  double energy_at(double s) override { return mean_energy(s); }

  Eigen::VectorXd gradient() override {
    const cudaStream_t s = stream_;
    HSI_CUDA_CHECK(kernels::gradient_samples(G_, g_.get(), ab_.get(), gab_.get(), s));
    // (∂/∂Re φ + i ∂/∂Im φ) E = Σ conj(D) (∂E/∂Re a + i ∂E/∂Im a): [gφ | gψ] = Dᴴ [ga | gb].
    HSI_CUDA_CHECK(kernels::tall_adjoint_times_two(G_, n_, D_, gab_.get(), coef_.get(), s));
    return download_coefficients(static_cast<double>(G_));
  }

  // Sample by sample on the device: [da | db] = D_rows p, each sample's Hessian applied
  // (kernels::hessian_apply), then D_rowsᴴ back as in gradient().
  Eigen::VectorXd hessian_times(HessianProjection projection, bool exact, bool all_samples, const Eigen::VectorXd& p) override {
    upload_coefficients(p, "Hessian product's");  // checks p's size (an InputError naming both sizes)
    const cudaStream_t s = stream_;
    if (!hv_in_.get()) {
      hv_in_ = DeviceArray<double2>(2 * sz(G_));
      hv_out_ = DeviceArray<double2>(2 * sz(G_));
    }
    const int rows = all_samples ? G_ : h_;
    const double2* R = all_samples ? D_ : DH_;
    HSI_CUDA_CHECK(kernels::tall_times_two(rows, n_, R, coef_.get(), hv_in_.get(), s));
    HSI_CUDA_CHECK(kernels::hessian_apply(rows, G_, all_samples ? nullptr : H_, g_.get(), ab_.get(), hv_in_.get(), to_device(projection),
                                          exact, hv_out_.get(), s));
    HSI_CUDA_CHECK(kernels::tall_adjoint_times_two(rows, n_, R, hv_out_.get(), coef_.get(), s));
    return download_coefficients(static_cast<double>(rows));
  }

  Eigen::MatrixXd hessian(HessianProjection projection, bool exact, bool all_samples) override {
    const cudaStream_t s = stream_;
    build_hessian(projection, exact, all_samples);
    const Eigen::Index N = 4 * static_cast<Eigen::Index>(n_);
    Eigen::MatrixXd out(N, N);
    HSI_CUDA_CHECK(cudaMemcpyAsync(out.data(), Hv_.get(), Hv_.bytes(), cudaMemcpyDeviceToHost, s));
    HSI_CUDA_CHECK(cudaStreamSynchronize(s));
    return out;
  }

  // newton_solve's reduced-space work on the device for the setup's spaces and
  // certifier (device_newton.cpp); null otherwise.
  std::unique_ptr<NewtonStepper> make_stepper(const MapSpace& space, const Certifier* certifier,
                                              const QuadraticTerm* quad) override;

  // The setup's certifier on the device (the frames' certificate); any other: the host's.
  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    if (!setup_ || !certifier_ || &certifier != &setup_->certifier) return std::nullopt;
    return certifier_->certify(map);
  }

  double max_safe_step() override {
    HSI_CUDA_CHECK(kernels::max_safe_step(G_, ab_.get(), dab_.get(), part_sum_.get(), done_.get(), scalar_.get(), stream_));
    return download_scalar();
  }

 private:
  friend class DeviceStepper;
  friend class BatchDeviceStepper;  // batch_stepper.cpp: the lockstep batch's stepper
  static constexpr cuDoubleComplex kOne{1, 0}, kZero{0, 0};

  // a = D φ, b = D ψ (or da, db) from v = (Re φ, Im φ, Re ψ, Im ψ): one GEMM D [φ | ψ].
  void apply_D(const Eigen::VectorXd& v, double2* out, const char* what) {
    upload_coefficients(v, what);
    HSI_CUDA_CHECK(kernels::tall_times_two(G_, n_, D_, coef_.get(), out, stream_));
  }
  // coef_ (n × 2 complex: [φ-like | ψ-like]) down, divided by count, in the v layout.
  Eigen::VectorXd download_coefficients(double count) {
    const cudaStream_t s = stream_;
    HSI_CUDA_CHECK(cudaMemcpyAsync(coef_down_.get(), coef_.get(), coef_.bytes(), cudaMemcpyDeviceToHost, s));
    HSI_CUDA_CHECK(cudaStreamSynchronize(s));
    const Eigen::Index n = n_;
    Eigen::VectorXd out(4 * n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const double2 gphi = coef_down_[static_cast<size_t>(j)], gpsi = coef_down_[static_cast<size_t>(n + j)];
      out(j) = gphi.x / count;
      out(n + j) = gphi.y / count;
      out(2 * n + j) = gpsi.x / count;
      out(3 * n + j) = gpsi.y / count;
    }
    return out;
  }
  // coef_ ← v (4n reals, v layout) as n × 2 complex [φ | ψ].
  void upload_coefficients(const Eigen::VectorXd& v, const char* what) {
    const Eigen::Index n = n_;
    if (v.size() != 4 * n)
      throw InputError(std::string("hsi::cuda: the ") + what + " vector has " + std::to_string(v.size()) + " entries, expected " +
                       std::to_string(4 * n));
    double2* c = coef_up_.begin_fill();
    for (Eigen::Index j = 0; j < n; ++j) {
      c[j] = make_double2(v(j), v(n + j));
      c[n + j] = make_double2(v(2 * n + j), v(3 * n + j));
    }
    coef_up_.send(coef_.get(), coef_.size(), stream_);
  }

  // Hv_ ← the real Hessian (4n × 4n), mean over H or, with all_samples, over all of G, on
  // the stream. Σ_H B_sᵀ K_s B_s in complex form is one GEMM D_Hᴴ [α_aa∘D, β_aa∘D̄,
  // α_ab∘D, β_ab∘D̄, α_bb∘D, β_bb∘D̄] (newton.cpp), then mapped to the real matrix on the
  // device. The all-samples buffers (|G| × 6n complex: 1.9 GB at |G| 40,000, n 500) are
  // made on the first escalation only (NewtonOptions::escalate_after_cuts).
  void build_hessian(HessianProjection projection, bool exact, bool all_samples) {
    const cudaStream_t s = stream_;
    if (all_samples) prepare_all_samples();
    const int rows = all_samples ? G_ : h_;
    const double2* DH = all_samples ? D_ : DH_;
    double2* Wt = all_samples ? Wt_all_.get() : Wt_.get();
    HSI_CUDA_CHECK(kernels::weighted_rows(G_, rows, n_, all_samples ? all_index_.get() : H_, g_.get(), ab_.get(),
                                          to_device(projection), exact, DH, all_samples ? W_all_.get() : W_.get(), Wt, s));
    HSI_CUDA_CHECK(cublasZgemm(blas_, CUBLAS_OP_C, CUBLAS_OP_N, n_, 6 * n_, rows, &kOne, DH, rows, Wt, rows, &kZero, R_.get(),
                               n_));
    HSI_CUDA_CHECK(kernels::real_hessian(n_, R_.get(), static_cast<double>(rows), Hv_.get(), s));
  }

  // The all-samples buffers, made on first use (synchronises once; outside any graph).
  void prepare_all_samples() {
    if (all_index_.get()) return;
    std::vector<int> iota(sz(G_));
    for (size_t i = 0; i < iota.size(); ++i) iota[i] = static_cast<int>(i);
    all_index_ = DeviceArray<int>(sz(G_));
    W_all_ = DeviceArray<double2>(6 * sz(G_));
    Wt_all_ = DeviceArray<double2>(sz(G_) * 6 * sz(n_));
    HSI_CUDA_CHECK(cudaMemcpyAsync(all_index_.get(), iota.data(), all_index_.bytes(), cudaMemcpyHostToDevice, stream_));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));  // iota is pageable host memory
  }

  double mean_energy(double s) {
    HSI_CUDA_CHECK(kernels::mean_energy(G_, g_.get(), ab_.get(), dab_.get(), s, part_sum_.get(), part_bad_.get(), done_.get(),
                                        scalar_.get(), stream_));
    return download_scalar();
  }

  double download_scalar() {
    HSI_CUDA_CHECK(cudaMemcpyAsync(scalar_down_.get(), scalar_.get(), sizeof(double), cudaMemcpyDeviceToHost, stream_));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
    return scalar_down_[0];
  }

  int G_, n_, h_;
  Stream stream_;                 // first: everything below is used on it
  BlasHandle blas_;
  std::shared_ptr<const SampleRows> rows_;  // D, D_H and H (shared with the setup's other cores on this GPU)
  const double2* D_ = nullptr;    // rows_->D: G × n, column-major (as Eigen stores it)
  const double2* DH_ = nullptr;   // rows_->DH: the rows H of D, |H| × n
  const int* H_ = nullptr;        // rows_->H: indices into G
  DeviceArray<double> g_;         // target metric (g1, g2, g3) per sample of G
  DeviceArray<double2> ab_;       // [a | b] = D [φ | ψ], G × 2
  DeviceArray<double2> dab_;      // [da | db], G × 2
  DeviceArray<double2> gab_;      // [∂E/∂a | ∂E/∂b] per sample, G × 2
  DeviceArray<double2> coef_;     // [φ | ψ] in, [gφ | gψ] out: n × 2
  DeviceArray<double2> W_;        // six Hessian weights per H-sample, 6 × |H|
  DeviceArray<double2> Wt_;       // the weighted rows, |H| × 6n
  DeviceArray<double2> R_;        // D_Hᴴ Wt, n × 6n
  DeviceArray<double> Hv_;        // the real Hessian, 4n × 4n
  DeviceArray<int> all_index_;    // 0 … |G|−1, and the all-samples weights and rows: build_hessian()
  DeviceArray<double2> W_all_, Wt_all_;
  DeviceArray<double2> hv_in_, hv_out_;  // hessian_times' [da | db] and per-sample products, 2 × |G| each (made on first use)
  DeviceArray<double> part_sum_;  // reduction partials (sums or minima)
  DeviceArray<int> part_bad_;
  DeviceArray<unsigned> done_;    // the one-launch reductions' counter (newton_kernels.h): 0 between launches
  DeviceArray<double> scalar_;
  Upload<double> targets_up_;
  Upload<double2> coef_up_;
  PinnedArray<double> scalar_down_;
  PinnedArray<double2> coef_down_;
  DeviceArray<double> keys_, log_keys_, weights_;  // set_target_keys' sets (K × G × 3) and blend weights
  std::unique_ptr<Upload<double>> weights_up_;
  int key_count_ = 0, log_key_count_ = 0;
  std::uint64_t target_token_ = 0;

  // Set-up work that would otherwise fall on the first solve (issue #23: the first frame
  // took 140–165 ms): every kernel and cuBLAS / cuSOLVER routine a solve uses runs once
  // here, at the sizes of a solve, on this core's stream and handles (so the modules
  // they load lazily are loaded, and the libraries' workspaces allocated), and with a
  // setup the device spaces of both its map spaces are made and a stepper is driven
  // through every call of an iteration from the identity map. Leaves the documented
  // initial state (a = b = 0, zero direction, identity targets). device_newton.cpp.
  void warm_up();

  // The device stepper (make_stepper()): what it needs beyond the per-call interface.
  DeviceSpace& device_space(const MapSpace& space);
  const ShapeSetup* setup_ = nullptr;
  SolverHandle solver_{stream_};
  std::unique_ptr<DeviceCertifier> certifier_;
  std::map<const MapSpace*, std::unique_ptr<DeviceSpace>> spaces_;
};


}  // namespace hsi::cuda
