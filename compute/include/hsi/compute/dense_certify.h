// Dense certification on the GPU (shaders/certify.comp): the local injectivity
// certificate of hsi::Certifier (engine/include/hsi/certificate.h, the CPU
// reference) with one shader invocation per boundary segment. Same segments
// (hsi::certificate_segments), same Lipschitz bound, same adaptive subdivision
// (depth first, the same depth cap and per-segment piece budget), same argument
// principle, reduced on the host by hsi::reduce_certificate into the same
// CertificateResult: verdict, failing loop / edge / point, margin and bounds.
//
// Precision: double only. The device must have shaderFloat64 (lavapipe, NVIDIA and
// AMD desktop GPUs do); without it the constructor throws VulkanError: use the CPU
// Certifier there. A float version is not offered because it could not keep the
// certificate sound.
//
// Soundness: the GPU test is the CPU's, rounding allowances included (error bounds on
// the evaluated f_z, f_zbar and derivatives, on the distances, Lipschitz constants and
// the few operations of each bound), all on the conservative side. The two evaluate
// f_z differently (the CPU per cage vertex, the GPU per cage edge) and so carry
// different allowances: the bounds differ by ~1e-11 of σ1 max (tests demand 1e-9), and
// a verdict can differ only for a map whose margin is within about that of zero.
#pragma once

#include <vector>

#include "hsi/certificate.h"
#include "hsi/compute/compute_pipeline.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

struct DenseCertifyOptions {
  // The map-independent half of the breakpoint values and Lipschitz constants is
  // precomputed once per shape as a matrix of breakpoints × (m + N) columns, 64 bytes
  // an entry (S = 10,000 breakpoints, m + N = 100: 64 MB); each map then costs one
  // matrix-vector product instead of a complex log per breakpoint and cage edge.
  // Above this size (or the device's maxStorageBufferRange) the values are computed
  // from the cage for every map instead (same verdicts, slower).
  VkDeviceSize max_basis_bytes = VkDeviceSize{1} << 30;
};

// Host wall-clock times of the last certify() call, in milliseconds.
struct DenseCertifyStats {
  double upload_ms = 0;    // packing and writing the coefficients and jump bounds
  double gpu_ms = 0;       // submit to fence: both passes (breakpoint values, segments)
  double device_ms = -1;   // GPU execution time of those passes (timestamps; < 0: not available)
  double readback_ms = 0;  // reading the segment outcomes and reducing them
};

// Per segment, as the shader reports it (finer than SegmentCertificate::ok).
enum class SegmentStatus : uint32_t {
  kCertified = 0,  // every piece proved
  kFolds = 1,      // |f_zbar| >= |f_z| at an end of the failing piece: a real fold
  kUndecided = 2,  // the depth cap or the piece budget was reached
  kSkipped = 3,    // not started: another segment had failed (stop_at_first_failure)
  kStopped = 4,    // interrupted: another segment had failed (stop_at_first_failure)
};

// Vulkan's MapCertifier (certificate.h): hsi/runtime/certifiers.h makes one by name.
class DenseCertifier : public MapCertifier {
 public:
  // Precomputes the segments and uploads them. The context must outlive this.
  // Throws VulkanError if the device has no shaderFloat64.
  DenseCertifier(const Context& context, const Shape& shape, const Cage& cage, const BoundarySamples& samples,
                 const DenseCertifyOptions& options = {});

  // As Certifier::certify. The map must have m + N coefficients (else InputError);
  // options.max_depth must be in [0, kMaxDepth] (else InputError).
  CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {}) override;
  const char* name() const override { return "vulkan"; }
  // certify() in two halves, for a caller that puts the certificate in its own
  // command buffer (e.g. one submission per frame with the evaluation and drawing):
  // record() packs and uploads the map and records both passes and the barrier to
  // host reads into `cmd`; after the caller has submitted `cmd` and waited for it,
  // collect() reads the outcomes back and reduces them. One record() per collect();
  // the map must stay unchanged in between only on the host side (it is copied).
  void record(VkCommandBuffer cmd, const HarmonicMap& map, const CertificateOptions& options = {});
  CertificateResult collect();

  static constexpr int kMaxDepth = 31;  // the shader's explicit stack holds 32 entries

  const CertificateSegments& segments() const { return segments_; }
  int breakpoint_count() const { return static_cast<int>(segments_.size()); }
  // Whether the precomputed basis matrix is used (see DenseCertifyOptions).
  bool uses_basis() const { return static_cast<bool>(basis_); }
  // The per-segment outcomes and statuses of the last certify() call.
  const std::vector<SegmentCertificate>& last_segments() const { return outcomes_; }
  const std::vector<SegmentStatus>& last_status() const { return status_; }
  const DenseCertifyStats& last_stats() const { return stats_; }

 private:
  const Context* context_;
  Cage cage_;
  CertificateSegments segments_;
  ComputePipeline pipeline_;
  DescriptorSet set_;
  std::vector<uint32_t> loops_host_;
  Buffer loops_, geom_, points_, next_, values_, out_, control_, readback_, lip_, basis_;
  std::vector<SegmentCertificate> outcomes_;
  std::vector<SegmentStatus> status_;
  DenseCertifyStats stats_;
  bool pending_nonfinite_ = false;  // record() saw a non-finite map: collect() reports it
};

}  // namespace hsi::compute
