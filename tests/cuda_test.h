// Shared by the CUDA test files: a test that needs a GPU skips with a warning (naming
// why) where there is none, so that CI without one passes.
#pragma once

#include <catch2/catch.hpp>
#include <string>

#include "hsi/cuda/newton_core.h"

#define HSI_REQUIRE_GPU()                            \
  do {                                               \
    std::string why_;                                \
    if (!hsi::cuda::device_available(&why_)) {       \
      WARN("skipped: " << why_);                     \
      return;                                        \
    }                                                \
  } while (0)
