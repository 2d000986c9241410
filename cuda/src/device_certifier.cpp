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
  const CertificateWeights w = certificate_weights(cage, seg);  // the weights as the CPU reference's
  set_up(cage, seg, rows.D, rows.E, w);
  rows_ = upload(cage, seg, rows.D, rows.E, w, stream_);
}

DeviceCertifier::DeviceCertifier(const hsi::Certifier& host, const Cage& cage, cudaStream_t stream, cublasHandle_t blas)
    : stream_(stream), blas_(blas) {
  set_up(cage, host.segments(), host.breakpoint_D(), host.breakpoint_E(), host.weights());
  rows_ = upload(cage, host.segments(), host.breakpoint_D(), host.breakpoint_E(), host.weights(), stream_);
}

DeviceCertifier::DeviceCertifier(const ShapeSetup& setup, cudaStream_t stream, cublasHandle_t blas, int capacity)
    : capacity_(capacity), stream_(stream), blas_(blas) {
  if (capacity < 1 || capacity > kernels::kMaxBatchSystems)
    throw InputError("hsi::cuda certificate: a batch of " + std::to_string(capacity) + " maps (1 to " +
                     std::to_string(kernels::kMaxBatchSystems) + ")");
  const hsi::Certifier& host = setup.certifier;
  set_up(setup.cage, host.segments(), host.breakpoint_D(), host.breakpoint_E(), host.weights());
  rows_ = std::static_pointer_cast<const Rows>(setup.shared_backend_data(device_key("certifier rows"), [&] {
    return upload(setup.cage, host.segments(), host.breakpoint_D(), host.breakpoint_E(), host.weights(), stream_);
  }));
}

void DeviceCertifier::set_up(const Cage& cage, const CertificateSegments& seg, const MatrixXcd& D, const MatrixXcd& E,
                             const CertificateWeights& w) {
  m_ = cage.vertex_count();
  N_ = cage.hole_count();
  M_ = m_ + N_;
  S_ = static_cast<int>(seg.size());
  loop_ = seg.loop;
  edge_ = seg.edge;
  // D, E, WD, WE: S × M; [W | Wh]: S × M (W over the cage's vertices, Wh its holes).
  const auto s_by_m = [&](const auto& X) { return X.rows() == S_ && X.cols() == M_; };
  if (!s_by_m(D) || !s_by_m(E) || !s_by_m(w.WD) || !s_by_m(w.WE) || w.W.rows() != S_ || w.Wh.rows() != S_ ||
      w.W.cols() + w.Wh.cols() != M_ || w.touches.size() != sz(S_))
    throw InputError("hsi::cuda certificate: the basis rows or weights do not match the segments and the cage");
  const size_t C = sz(capacity_);
  coef_ = DeviceArray<double2>(2 * sz(M_));
  values_ = DeviceArray<double2>(4 * sz(S_) * C);
  errs_ = DeviceArray<double>(4 * sz(S_) * C);
  jumps_ = DeviceArray<double>(2 * sz(M_) * C);
  abs_coef_ = DeviceArray<double>(2 * sz(M_) * C);
  lip_ = DeviceArray<double>(2 * sz(S_) * C);
  outcomes_ = DeviceArray<kernels::SegmentOutcome>(sz(S_) * C);
  partials_ = DeviceArray<unsigned char>(kernels::reduce_partials_bytes() * C);
  stop_ = DeviceArray<int>(C);
  done_ = DeviceArray<unsigned>(C);
  HSI_CUDA_CHECK(cudaMemsetAsync(done_.get(), 0, done_.bytes(), stream_));  // reduce_certificate's counters
  summary_down_ = PinnedArray<kernels::CertifySummary>(C);
  coef_up_ = PinnedArray<double2>(2 * sz(M_));
}

std::shared_ptr<DeviceCertifier::Rows> DeviceCertifier::upload(const Cage& cage, const CertificateSegments& seg, const MatrixXcd& D,
                                                               const MatrixXcd& E, const CertificateWeights& w, cudaStream_t stream) {
  const Eigen::Index S = static_cast<Eigen::Index>(seg.size()), M = D.cols();
  std::vector<cd> z;
  std::vector<int> begin{0};
  for (const Loop& l : cage.loops) {
    z.insert(z.end(), l.begin(), l.end());
    begin.push_back(static_cast<int>(z.size()));
  }
  MatrixXcd DE(2 * S, M);
  DE << D, E;
  Eigen::MatrixXd WDE(2 * S, M), WWh(S, M);
  WDE << w.WD, w.WE;
  WWh << w.W, w.Wh;

  auto r = std::make_shared<Rows>();
  r->z = DeviceArray<double2>(z.size());
  r->holes = DeviceArray<double2>(std::max<size_t>(1, cage.hole_points.size()));
  r->points = DeviceArray<double2>(seg.size());
  r->loop_begin = DeviceArray<int>(begin.size());
  r->next = DeviceArray<int>(seg.size());
  r->DE = DeviceArray<double2>(static_cast<size_t>(DE.size()));
  r->WDE = DeviceArray<double>(static_cast<size_t>(WDE.size()));
  r->WWh = DeviceArray<double>(static_cast<size_t>(WWh.size()));
  r->touches = DeviceArray<char>(seg.size());

  static_assert(sizeof(cd) == sizeof(double2));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->z.get(), z.data(), r->z.bytes(), cudaMemcpyHostToDevice, stream));
  if (!cage.hole_points.empty())
    HSI_CUDA_CHECK(cudaMemcpyAsync(r->holes.get(), cage.hole_points.data(), cage.hole_points.size() * sizeof(double2),
                                   cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->points.get(), seg.points.data(), r->points.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->loop_begin.get(), begin.data(), r->loop_begin.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->next.get(), seg.next.data(), r->next.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->DE.get(), DE.data(), r->DE.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->WDE.get(), WDE.data(), r->WDE.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->WWh.get(), WWh.data(), r->WWh.bytes(), cudaMemcpyHostToDevice, stream));
  HSI_CUDA_CHECK(cudaMemcpyAsync(r->touches.get(), w.touches.data(), r->touches.bytes(), cudaMemcpyHostToDevice, stream));
  // The host vectors above are pageable, and other streams read the copy: done before returning.
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
  return r;
}

kernels::CageView DeviceCertifier::cage_view() const {
  return {rows_->z.get(), rows_->loop_begin.get(), static_cast<int>(rows_->loop_begin.size()) - 1, m_, rows_->holes.get(), N_};
}
kernels::SegmentsView DeviceCertifier::segments_view() const { return {rows_->points.get(), rows_->next.get(), S_}; }

void DeviceCertifier::enqueue(const double2* coef, const CertificateOptions& options, int maps) {
  check_maps(maps);
  if (options.max_depth > kernels::kMaxCertifyDepth)
    throw InputError("hsi::cuda certificate: max_depth " + std::to_string(options.max_depth) + " exceeds the GPU's " +
                     std::to_string(kernels::kMaxCertifyDepth));
  const cudaStream_t s = stream_;
  // Values at the breakpoints: [a | a1 | b | b1] = [D; E] · [φ | ψ] (a tall product).
  HSI_CUDA_CHECK(kernels::tall_times_two_batched(maps, 2 * S_, M_, rows_->DE.get(), coef, values_.get(), s));
  // Lipschitz constants of f_zz and (conj f_zbar)' per segment: [W | Wh] · jumps; the
  // values' rounding weights: [WD; WE] · [|φ| | |ψ|].
  int* stop = options.stop_at_first_failure ? stop_.get() : nullptr;  // cleared by lipschitz_jumps
  HSI_CUDA_CHECK(kernels::lipschitz_jumps_batched(maps, cage_view(), coef, jumps_.get(), abs_coef_.get(), stop, s));
  // Every map's two columns side by side (M × 2·maps, S × 2·maps): one product each.
  const double one = 1, zero = 0;
  HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, S_, 2 * maps, M_, &one, rows_->WWh.get(), S_, jumps_.get(), M_, &zero,
                             lip_.get(), S_));
  HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, 2 * S_, 2 * maps, M_, &one, rows_->WDE.get(), 2 * S_, abs_coef_.get(),
                             M_, &zero, errs_.get(), 2 * S_));
  HSI_CUDA_CHECK(kernels::certify_segments_batched(maps, cage_view(), segments_view(), coef, values_.get(), errs_.get(), lip_.get(),
                                                   rows_->touches.get(), options.max_depth, options.max_pieces_per_segment, stop,
                                                   outcomes_.get(), s));
  // The summaries straight into pinned host memory (mapped: no copy), read by fetch().
  HSI_CUDA_CHECK(kernels::reduce_certificate_batched(maps, S_, outcomes_.get(), values_.get(), partials_.get(), done_.get(),
                                                     summary_down_.get(), s));
}

void DeviceCertifier::check_maps(int maps) const {
  if (maps < 1 || maps > capacity_)
    throw InputError("hsi::cuda certificate: " + std::to_string(maps) + " maps for a certifier of " + std::to_string(capacity_));
}

CertificateResult DeviceCertifier::fetch() {
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
  return result(summary_down_[0]);
}

std::vector<CertificateResult> DeviceCertifier::fetch_all(int maps) {
  check_maps(maps);
  HSI_CUDA_CHECK(cudaStreamSynchronize(stream_));
  std::vector<CertificateResult> out;
  out.reserve(sz(maps));
  for (int s = 0; s < maps; ++s) out.push_back(result(summary_down_[sz(s)]));
  return out;
}

CertificateResult DeviceCertifier::result(const kernels::CertifySummary& k) const {
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
  explicit Impl(const ShapeSetup& s) : certifier(s, stream, blas) {}
};

Certifier::Certifier(const ShapeSetup& s) : impl_(std::make_unique<Impl>(s)) {}
Certifier::Certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples)
    : impl_(std::make_unique<Impl>(shape, cage, samples)) {}
Certifier::~Certifier() = default;
CertificateResult Certifier::certify(const HarmonicMap& map, const CertificateOptions& options) {
  return impl_->certifier.certify(map, options);
}

}  // namespace hsi::cuda
