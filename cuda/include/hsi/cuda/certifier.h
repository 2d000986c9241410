// The local injectivity certificate on the GPU: the same Lipschitz test with adaptive
// subdivision and the same argument-principle check as hsi::Certifier (the CPU
// reference, certificate.h), one thread per boundary segment, reduced on the device.
// The CUDA Newton core uses it inside its line search; this class is CUDA's
// MapCertifier (hsi/runtime/certifiers.h makes one by name).
#pragma once

#include <memory>

#include "hsi/certificate.h"
#include "hsi/shape_setup.h"

namespace hsi::cuda {

class Certifier final : public MapCertifier {
 public:
  // Uploads the setup's segments, basis rows and distance weights once. Throws
  // hsi::cuda::Error if the device cannot be used.
  explicit Certifier(const ShapeSetup& setup);
  Certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples);  // as hsi::Certifier's
  ~Certifier();
  Certifier(const Certifier&) = delete;
  Certifier& operator=(const Certifier&) = delete;

  // The verdict, failing place and bounds, as hsi::Certifier::certify would give them
  // (up to round-off in the bounds). options.max_depth is at most 24 here.
  CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {}) override;
  const char* name() const override { return "cuda"; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hsi::cuda
