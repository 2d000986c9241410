// Diagnostic drawings (cairo, PNG): a shape with its cage, hole points and samples.
#pragma once

#include <filesystem>

#include "hsi/cage.h"
#include "hsi/samples.h"

namespace hsi::cli {

void plot_cage(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const BoundarySamples* samples,
               int width_px = 800);

}  // namespace hsi::cli

#include "hsi/harmonic_map.h"

namespace hsi::cli {

// The image of the shape under a map: its boundary filled, the images of grid
// lines of the rest shape (to show the deformation), handles and their targets.
struct MapPlot {
  std::vector<cd> handles_image;  // where the handles went (drawn as dots)
  std::vector<cd> targets;        // their targets (drawn as rings)
  std::string title;
  bool uncertified = false;       // draws the fill in red and says so
};
void plot_map(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const HarmonicMap& map,
              const MapPlot& extras = {}, int width_px = 800);

}  // namespace hsi::cli
