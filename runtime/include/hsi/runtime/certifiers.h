// The certifier factory: the local injectivity certificate (hsi/certificate.h) of a
// backend picked by name, behind the one MapCertifier interface. "cpu" is the
// reference, always there; "cuda" needs a CUDA build and device; "vulkan" (the dense
// certify of compute/) a Vulkan build and a device with shaderFloat64 (lavapipe has it).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "hsi/certificate.h"

namespace hsi::runtime {

// "cpu", "cuda", "vulkan".
std::span<const std::string_view> certifier_names();

// Whether make_certifier(name, ...) can work here; if not, why (never throws for a
// valid name; InputError for another). "vulkan" is answered by making a context.
bool certifier_available(std::string_view name, std::string* why = nullptr);

struct CertifierOptions {
  bool vulkan_validation = false;  // "vulkan": the Khronos validation layer on (see validation_messages)
  std::string vulkan_device;       // "vulkan": a device whose name contains this (empty: HSI_VULKAN_DEVICE, else the best)
};

// The certifier for the shape, cage and samples (copied or uploaded: they need not
// outlive it). Throws InputError for a name not in certifier_names() (naming them) and
// BackendUnavailable (hsi/runtime/backend.h) with the reason where the backend cannot run.
std::unique_ptr<MapCertifier> make_certifier(std::string_view name, const Shape& shape, const Cage& cage,
                                             const BoundarySamples& samples, const CertifierOptions& options = {});

// For a "vulkan" certifier made with validation: the validation layer's messages so far
// (empty when there were none, or for other certifiers).
std::string validation_messages(const MapCertifier& certifier);

}  // namespace hsi::runtime
