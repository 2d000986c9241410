// The certifier factory (see certifiers.h). HSI_RUNTIME_CUDA / HSI_RUNTIME_VULKAN are
// set by runtime/CMakeLists.txt when cuda/ / compute/ are built.
#include "hsi/runtime/certifiers.h"

#include <array>

#include "hsi/domain.h"
#include "hsi/runtime/backend.h"
#include "built.h"
#if HSI_RUNTIME_CUDA
#include "hsi/cuda/certifier.h"
#endif
#if HSI_RUNTIME_VULKAN
#include "hsi/compute/dense_certify.h"
#include "hsi/compute/vulkan_context.h"
#endif

namespace hsi::runtime {

namespace {

constexpr std::array<std::string_view, 3> kNames = {"cpu", "cuda", "vulkan"};

void check_name(std::string_view name) {
  for (std::string_view n : kNames)
    if (n == name) return;
  throw InputError("certifier '" + std::string(name) + "' is not one of cpu, cuda, vulkan");
}

#if HSI_RUNTIME_VULKAN
namespace gpu = hsi::compute;

gpu::ContextOptions context_options(const CertifierOptions& o) {
  gpu::ContextOptions co;
  co.validation = o.vulkan_validation;
  co.device_name = o.vulkan_device;
  return co;
}

// The dense certifier with the context it runs on (made first, destroyed last).
struct ContextHolder {
  std::unique_ptr<gpu::Context> context;
};
class VulkanCertifier final : private ContextHolder, public gpu::DenseCertifier {
 public:
  VulkanCertifier(std::unique_ptr<gpu::Context> ctx, const Shape& shape, const Cage& cage, const BoundarySamples& samples)
      : ContextHolder{std::move(ctx)}, gpu::DenseCertifier(*context, shape, cage, samples) {}
  std::string messages() const {
    return context->validation_enabled() && context->validation_log()->count() ? context->validation_log()->summary(10) : "";
  }
};

std::unique_ptr<gpu::Context> vulkan_context(const CertifierOptions& o) {
  std::unique_ptr<gpu::Context> ctx;
  try {
    ctx = std::make_unique<gpu::Context>(context_options(o));
  } catch (const gpu::VulkanUnavailable& e) {
    throw BackendUnavailable(std::string("certifier vulkan: no Vulkan device: ") + e.what());
  }
  if (!ctx->info().float64)
    throw BackendUnavailable("certifier vulkan: " + ctx->info().name + " has no shaderFloat64, which the certificate needs");
  return ctx;
}
#endif

}  // namespace

std::span<const std::string_view> certifier_names() { return kNames; }

bool certifier_available(std::string_view name, std::string* why) {
  check_name(name);
  std::string reason;  // empty: available
  if (name == "cuda") {
    const CudaStatus s = cuda_status();
    if (!s.available) reason = s.detail;
  } else if (name == "vulkan") {
#if HSI_RUNTIME_VULKAN
    try {
      vulkan_context({});
    } catch (const std::exception& e) {
      reason = e.what();
    }
#else
    reason = built::kNoVulkan;
#endif
  }
  if (why) *why = reason;
  return reason.empty();
}

std::unique_ptr<MapCertifier> make_certifier(std::string_view name, const Shape& shape, const Cage& cage,
                                             const BoundarySamples& samples, const CertifierOptions& options) {
  check_name(name);
  if (name == "cpu") return make_cpu_certifier(shape, cage, samples);
  if (name == "cuda") {
    const CudaStatus s = cuda_status();
    if (!s.available) throw BackendUnavailable("certifier cuda: " + s.detail);
#if HSI_RUNTIME_CUDA
    return std::make_unique<hsi::cuda::Certifier>(shape, cage, samples);
#endif
  }
#if HSI_RUNTIME_VULKAN
  if (name == "vulkan") return std::make_unique<VulkanCertifier>(vulkan_context(options), shape, cage, samples);
#else
  (void)options;
  if (name == "vulkan") throw BackendUnavailable(std::string("certifier vulkan: ") + built::kNoVulkan);
#endif
  throw BackendUnavailable("certifier " + std::string(name) + ": not in this build");
}

std::string validation_messages(const MapCertifier& certifier) {
#if HSI_RUNTIME_VULKAN
  if (const auto* v = dynamic_cast<const VulkanCertifier*>(&certifier)) return v->messages();
#else
  (void)certifier;
#endif
  return "";
}

}  // namespace hsi::runtime
