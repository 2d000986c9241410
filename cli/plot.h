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

namespace hsi::cli {

struct Series {
  std::string name;
  std::vector<double> y;
  double r = 0.1, g = 0.3, b = 0.7;
  bool dashed = false;
};

// A line plot of series over x, with axes, ticks, legend and red markers at
// `flagged` x positions (e.g. frames that could not be certified).
void plot_series(const std::filesystem::path& png, const std::string& title, const std::string& xlabel,
                 const std::vector<double>& x, const std::vector<Series>& series, const std::vector<double>& flagged = {},
                 int width_px = 900, int height_px = 420);

}  // namespace hsi::cli
