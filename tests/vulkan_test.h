// The harness every Vulkan test runs in: a context with the validation layer (and
// synchronisation validation) on, destroyed before the check so that teardown
// messages such as leaked objects are caught too; any validation message fails the
// test. Without a Vulkan device the test is skipped with a warning, unless
// HSI_REQUIRE_VULKAN=1 (CI) makes that a failure.
#pragma once

#include <catch2/catch.hpp>

#include <cstdlib>
#include <memory>
#include <string>

#include "hsi/compute/vulkan_context.h"

namespace hsi::test {

// An environment switch: set, non-empty and not "0".
inline bool env_set(const char* name) {
  const char* env = std::getenv(name);
  return env && *env && std::string(env) != "0";
}

template <class Body>
void with_vulkan(Body&& body, compute::ContextOptions options = {}) {
  options.validation = true;
  std::shared_ptr<compute::ValidationLog> log;
  {
    std::unique_ptr<compute::Context> ctx;
    try {
      ctx = std::make_unique<compute::Context>(options);
    } catch (const compute::VulkanUnavailable& e) {
      if (env_set("HSI_REQUIRE_VULKAN")) FAIL("HSI_REQUIRE_VULKAN is set but: " << e.what());
      WARN("skipping Vulkan test: " << e.what());
      return;
    }
    log = ctx->validation_log();
    body(*ctx);
  }
  INFO(log->summary(10));
  CHECK(log->count() == 0);
}

}  // namespace hsi::test
