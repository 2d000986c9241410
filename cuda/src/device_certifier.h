// The certificate on the GPU (certify_kernels.cu behind a host class): the shape's
// segments, the basis rows D and E at the breakpoints and the Lipschitz distance
// weights live on the device; a certification reads the map's full coefficients from
// device memory and returns one small summary. Host code, not thread-safe.
#pragma once

#include <memory>
#include <vector>

#include "certify_kernels.h"
#include "device.h"
#include "hsi/certificate.h"
#include "hsi/shape_setup.h"

namespace hsi::cuda {

class DeviceCertifier {
 public:
  DeviceCertifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples, cudaStream_t stream,
                  cublasHandle_t blas);
  // The same from a host certifier of the same shape, cage and samples (a ShapeSetup's):
  // its segments, basis rows and weights uploaded as they are, not evaluated again.
  DeviceCertifier(const hsi::Certifier& host, const Cage& cage, cudaStream_t stream, cublasHandle_t blas);
  // The same from a setup's certifier, its rows on the device shared by every
  // DeviceCertifier made from that setup on this GPU (ShapeSetup::shared_backend_data):
  // uploaded by the first, read only by all.
  // `capacity`: the most maps one enqueue() certifies at once (a lockstep batch's maps,
  // issue #23); the per-map buffers are made for that many.
  DeviceCertifier(const ShapeSetup& setup, cudaStream_t stream, cublasHandle_t blas, int capacity = 1);

  int coefficient_count() const { return M_; }  // M = m + N complex per φ and ψ
  int segment_count() const { return S_; }
  int capacity() const { return capacity_; }

  // Enqueues the certificate of the map whose full coefficients [φ | ψ] (M × 2 complex,
  // column-major) are at `coef` on the device; fetch() waits and returns the verdict.
  // With `maps` > 1 (at most capacity()), the maps at coef + 2M·s for s < maps, all in
  // the launches one map takes; fetch_all() returns each map's verdict, what enqueue()
  // and fetch() give for that map alone (the verdict, the failing segment and the counts;
  // the bounds too, bit for bit in every case tested on an H100, though cuBLAS may sum the
  // two small weight products over 2·maps columns in another order than over two).
  void enqueue(const double2* coef, const CertificateOptions& options, int maps = 1);
  CertificateResult fetch();
  std::vector<CertificateResult> fetch_all(int maps);

  // Convenience for tests and benchmarks: upload the map, enqueue, fetch.
  CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {});

 private:
  // What a certification only reads: the cage, the segments, the basis rows and their
  // weights at the breakpoints.
  struct Rows {
    DeviceArray<double2> z, holes, points;
    DeviceArray<int> loop_begin, next;
    DeviceArray<double2> DE;        // [D; E] at the breakpoints, 2S × M
    DeviceArray<double> WDE;        // [WD; WE], the rounding weights of [D; E], 2S × M
    DeviceArray<double> WWh;        // [W | Wh], S × M (hsi::certificate_weights)
    DeviceArray<char> touches;      // per segment: a distance bound is not positive
  };
  // Rows uploaded on `stream` (synchronised before it returns: the host data is pageable).
  static std::shared_ptr<Rows> upload(const Cage& cage, const CertificateSegments& seg, const MatrixXcd& D, const MatrixXcd& E,
                                      const CertificateWeights& w, cudaStream_t stream);
  // Checks the sizes, sets the counts and makes this certifier's own buffers.
  void set_up(const Cage& cage, const CertificateSegments& seg, const MatrixXcd& D, const MatrixXcd& E, const CertificateWeights& w);
  CertificateResult result(const kernels::CertifySummary& k) const;
  void check_maps(int maps) const;  // InputError unless 1 ≤ maps ≤ capacity()

  int m_ = 0, N_ = 0, M_ = 0, S_ = 0, capacity_ = 1;
  cudaStream_t stream_;
  cublasHandle_t blas_;
  std::vector<int> loop_, edge_;  // per segment, to name a failure
  std::shared_ptr<const Rows> rows_;
  DeviceArray<double2> coef_;      // upload target of certify()
  // Per map (capacity_ of each, one after another):
  DeviceArray<double2> values_;    // [a | a1 | b | b1], S × 4 (= 2S × 2)
  DeviceArray<double> errs_;       // their rounding weights, the same layout
  DeviceArray<double> jumps_;      // M × 2
  DeviceArray<double> abs_coef_;   // [|φ| | |ψ|], M × 2
  DeviceArray<double> lip_;        // S × 2
  DeviceArray<kernels::SegmentOutcome> outcomes_;
  DeviceArray<unsigned char> partials_;  // the summary's first pass
  DeviceArray<int> stop_;
  DeviceArray<unsigned> done_;     // reduce_certificate's counter: 0 between launches
  PinnedArray<kernels::CertifySummary> summary_down_;
  PinnedArray<double2> coef_up_;

  kernels::CageView cage_view() const;
  kernels::SegmentsView segments_view() const;
};

}  // namespace hsi::cuda
