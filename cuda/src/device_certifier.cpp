// DeviceCertifier: see device_certifier.h. The arithmetic is certify_kernels.cu; this
// file uploads the shape once and turns the device's summary into a CertificateResult
// worded like the CPU's.
#include "device_certifier.h"

#include <cmath>
#include <numbers>
#include <sstream>

#include "hsi/basis.h"
#include "newton_kernels.h"

namespace hsi::cuda {
namespace {
size_t sz(int v) { return static_cast<size_t>(v); }
}  // namespace

DeviceCertifier::DeviceCertifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples, cudaStream_t stream,
                                 cublasHandle_t blas)
    : stream_(stream), blas_(blas) {
  const CertificateSegments seg = certificate_segments(shape, samples);
  const BasisRows rows = evaluate_basis(cage, seg.points, kBasisD | kBasisE);
  upload(cage, seg, rows.D, rows.E, certificate_weights(cage, seg));  // the weights as the CPU reference's
}

DeviceCertifier::DeviceCertifier(const hsi::Certifier& host, const Cage& cage, cudaStream_t stream, cublasHandle_t blas)
    : stream_(stream), blas_(blas) {
  upload(cage, host.segments(), host.breakpoint_D(), host.breakpoint_E(), host.weights());
}

void DeviceCertifier::upload(const Cage& cage, const CertificateSegments& seg, const MatrixXcd& D, const MatrixXcd& E,
                             const CertificateWeights& w) {
  m_ = cage.vertex_count();
  N_ = cage.hole_count();
  M_ = m_ + N_;
  S_ = static_cast<int>(seg.size());
  loop_ = seg.loop;
  edge_ = seg.edge;
  std::vector<cd> z;
  std::vector<int> begin{0};
  for (const Loop& l : cage.loops) {
    z.insert(z.end(), l.begin(), l.end());
    begin.push_back(static_cast<int>(z.size()));
  }
  // D, E, WD, WE: S × M; [W | Wh]: S × M (W over the cage's vertices, Wh its holes).
  const auto s_by_m = [&](const auto& X) { return X.rows() == S_ && X.cols() == M_; };
  if (!s_by_m(D) || !s_by_m(E) || !s_by_m(w.WD) || !s_by_m(w.WE) || w.W.rows() != S_ || w.Wh.rows() != S_ ||
      w.W.cols() + w.Wh.cols() != M_ || w.touches.size() != sz(S_))
    throw InputError("hsi::cuda certificate: the basis rows or weights do not match the segments and the cage");
  MatrixXcd DE(2 * static_cast<Eigen::Index>(S_), M_);
  DE << D, E;
  Eigen::MatrixXd WDE(2 * static_cast<Eigen::Index>(S_), M_), WWh(static_cast<Eigen::Index>(S_), M_);
  WDE << w.WD, w.WE;
  WWh << w.W, w.Wh;

  z_ = DeviceArray<double2>(z.size());
  holes_ = DeviceArray<double2>(std::max<size_t>(1, cage.hole_points.size()));
  points_ = DeviceArray<double2>(sz(S_));
  loop_begin_ = DeviceArray<int>(begin.size());
  next_ = DeviceArray<int>(sz(S_));
  DE_ = DeviceArray<double2>(2 * sz(S_) * sz(M_));
  WDE_ = DeviceArray<double>(2 * sz(S_) * sz(M_));
  WWh_ = DeviceArray<double>(sz(S_) * sz(M_));
  touches_ = DeviceArray<char>(sz(S_));
  coef_ = DeviceArray<double2>(2 * sz(M_));
  values_ = DeviceArray<double2>(4 * sz(S_));
  errs_ = DeviceArray<double>(4 * sz(S_));
  jumps_ = DeviceArray<double>(2 * sz(M_));
  abs_coef_ = DeviceArray<double>(2 * sz(M_));
  lip_ = DeviceArray<double>(2 * sz(S_));
  outcomes_ = DeviceArray<kernels::SegmentOutcome>(sz(S_));
  summary_ = DeviceArray<kernels::CertifySummary>(1);
  partials_ = DeviceArray<unsigned char>(kernels::reduce_partials_bytes());
  stop_ = DeviceArray<int>(1);
  summary_down_ = PinnedArray<kernels::CertifySummary>(1);
  coef_up_ = PinnedArray<double2>(2 * sz(M_));

  static_assert(sizeof(cd) == sizeof(double2));
  HSI_CUDA_CHECK(cudaMemcpyAsync(z_.get(), z.data(), z_.bytes(), cudaMemcpyHostToDevice, stream_));
  if (N_ > 0)
    HSI_CUDA_CHECK(cudaMemcpyAsync(holes_.get(), cage.hole_points.data(), sz(N_) * sizeof(double2), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(points_.get(), seg.points.data(), points_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(loop_begin_.get(), begin.data(), loop_begin_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(next_.get(), seg.next.data(), next_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(DE_.get(), DE.data(), DE_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(WDE_.get(), WDE.data(), WDE_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(WWh_.get(), WWh.data(), WWh_.bytes(), cudaMemcpyHostToDevice, stream_));
  HSI_CUDA_CHECK(cudaMemcpyAsync(touches_.get(), w.touches.data(), touches_.bytes(), cudaMemcpyHostToDevice, stream_));
  // The host vectors above are pageable: done with them before they go.
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

kernels::CageView DeviceCertifier::cage_view() const {
  return {z_.get(), loop_begin_.get(), static_cast<int>(loop_begin_.size()) - 1, m_, holes_.get(), N_};
}
kernels::SegmentsView DeviceCertifier::segments_view() const { return {points_.get(), next_.get(), S_}; }

void DeviceCertifier::enqueue(const double2* coef, const CertificateOptions& options) {
  if (options.max_depth > kernels::kMaxCertifyDepth)
    throw InputError("hsi::cuda certificate: max_depth " + std::to_string(options.max_depth) + " exceeds the GPU's " +
                     std::to_string(kernels::kMaxCertifyDepth));
  const cudaStream_t s = stream_;
  // Values at the breakpoints: [a | a1 | b | b1] = [D; E] · [φ | ψ] (a tall product).
  HSI_CUDA_CHECK(kernels::tall_times_two(2 * S_, M_, DE_.get(), coef, values_.get(), s));
  // Lipschitz constants of f_zz and (conj f_zbar)' per segment: [W | Wh] · jumps; the
  // values' rounding weights: [WD; WE] · [|φ| | |ψ|].
  HSI_CUDA_CHECK(kernels::lipschitz_jumps(cage_view(), coef, jumps_.get(), abs_coef_.get(), s));
  const double one = 1, zero = 0;
  HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, S_, 2, M_, &one, WWh_.get(), S_, jumps_.get(), M_, &zero,
                             lip_.get(), S_));
  HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, 2 * S_, 2, M_, &one, WDE_.get(), 2 * S_, abs_coef_.get(), M_,
                             &zero, errs_.get(), 2 * S_));
  int* stop = nullptr;
  if (options.stop_at_first_failure) {
    HSI_CUDA_CHECK(cudaMemsetAsync(stop_.get(), 0, sizeof(int), s));
    stop = stop_.get();
  }
  HSI_CUDA_CHECK(kernels::certify_segments(cage_view(), segments_view(), coef, values_.get(), errs_.get(), lip_.get(),
                                           touches_.get(), options.max_depth, options.max_pieces_per_segment, stop,
                                           outcomes_.get(), s));
  HSI_CUDA_CHECK(kernels::reduce_certificate(S_, outcomes_.get(), values_.get(), partials_.get(), summary_.get(), s));
  HSI_CUDA_CHECK(cudaMemcpyAsync(summary_down_.get(), summary_.get(), sizeof(kernels::CertifySummary), cudaMemcpyDeviceToHost, s));
}

CertificateResult DeviceCertifier::fetch() {
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const kernels::CertifySummary& k = summary_down_[0];
  CertificateResult r;
  r.segments = k.segments;
  r.subdivisions = k.subdivisions;
  r.min_margin = k.min_margin;
  r.sigma1_max = k.sigma1_max;
  r.sigma2_min = k.sigma2_min;
  r.k_max = k.k_max;
  r.observed_sigma1_max = k.observed_sigma1_max;
  r.observed_sigma2_min = k.observed_sigma2_min;
  r.observed_k_max = k.observed_k_max;
  r.observed_isometric_max = k.observed_isometric_max;
  r.certified = k.first_fail >= S_;
  if (!r.certified) {
    r.fail_loop = loop_[sz(k.first_fail)];
    r.fail_edge = edge_[sz(k.first_fail)];
    r.fail_point = cd(k.fail_point.x, k.fail_point.y);
  }
  return finish_certificate(std::move(r), k.arg_total);
}

CertificateResult DeviceCertifier::certify(const HarmonicMap& map, const CertificateOptions& options) {
  if (map.phi.size() != M_ || map.psi.size() != M_)
    throw InputError("certificate: the map has " + std::to_string(map.phi.size()) + " coefficients; the cage needs " +
                     std::to_string(M_));
  if (!map.phi.allFinite() || !map.psi.allFinite()) {
    CertificateResult r;
    r.reason = "the map's coefficients are not finite";
    return r;
  }
  std::copy(map.phi.data(), map.phi.data() + M_, reinterpret_cast<cd*>(coef_up_.get()));
  std::copy(map.psi.data(), map.psi.data() + M_, reinterpret_cast<cd*>(coef_up_.get()) + M_);
  HSI_CUDA_CHECK(cudaMemcpyAsync(coef_.get(), coef_up_.get(), coef_.bytes(), cudaMemcpyHostToDevice, stream_));
  enqueue(coef_.get(), options);
  return fetch();
}

}  // namespace hsi::cuda

#include "hsi/cuda/certifier.h"

namespace hsi::cuda {

struct Certifier::Impl {
  Stream stream;
  BlasHandle blas{stream};
  DeviceCertifier certifier;
  Impl(const Shape& shape, const Cage& cage, const BoundarySamples& samples) : certifier(shape, cage, samples, stream, blas) {}
  explicit Impl(const ShapeSetup& s) : certifier(s.certifier, s.cage, stream, blas) {}
};

Certifier::Certifier(const ShapeSetup& s) : impl_(std::make_unique<Impl>(s)) {}
Certifier::Certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples)
    : impl_(std::make_unique<Impl>(shape, cage, samples)) {}
Certifier::~Certifier() = default;
CertificateResult Certifier::certify(const HarmonicMap& map, const CertificateOptions& options) {
  return impl_->certifier.certify(map, options);
}

}  // namespace hsi::cuda
