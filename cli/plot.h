// Diagnostic drawings (cairo, PNG): a shape with its cage, hole points and samples.
#pragma once

#include <filesystem>

#include "hsi/cage.h"
#include "hsi/samples.h"

namespace hsi::cli {

void plot_cage(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const BoundarySamples* samples,
               int width_px = 800);

}  // namespace hsi::cli
