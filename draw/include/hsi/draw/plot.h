// Diagnostic drawings (cairo, PNG): a shape with its cage, hole points and samples.
#pragma once

#include <filesystem>

#include "hsi/cage.h"
#include "hsi/samples.h"
#include "hsi/scene_texture.h"

namespace hsi::draw {

// What plot_cage draws besides the shape, its cage, hole points and samples.
struct CagePlot {
  // A scene's sprite (not the checkerboard): drawn under the outline with the scene's
  // filter, so that the outline and the handles can be checked against the art; the
  // shape is then only tinted.
  const SceneTexture* texture = nullptr;
  std::vector<cd> handles;  // drawn as numbered dots
};
void plot_cage(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const BoundarySamples* samples,
               int width_px = 800, const CagePlot& extras = {});

}  // namespace hsi::draw

#include "hsi/harmonic_map.h"

namespace hsi::draw {

// The image of the shape under a map: its boundary filled, the images of grid
// lines of the rest shape (to show the deformation), handles and their targets.
struct MapPlot {
  std::vector<cd> handles_image;  // where the handles went (drawn as dots)
  std::vector<cd> targets;        // their targets (drawn as rings)
  std::string title;
  bool uncertified = false;       // draws the fill in red and says so
  bool overlaps = false;          // the boundary's image crosses itself (overlap.h): amber border and label
  bool not_converged = false;     // says "NOT CONVERGED" in orange (the Newton solve stopped early)
  // The scene's texture, drawn through the map (piecewise affine on a triangulation of
  // the rest shape, with the scene's filter) under the outline; null: a flat fill.
  const SceneTexture* texture = nullptr;
};
void plot_map(const std::filesystem::path& png, const Shape& shape, const Cage& cage, const HarmonicMap& map,
              const MapPlot& extras = {}, int width_px = 800);

}  // namespace hsi::draw

namespace hsi::draw {

struct Series {
  std::string name;
  std::vector<double> y;  // one per x; NaN: a gap; +inf: a marker on the top edge (e.g. a folded frame)
  double r = 0.1, g = 0.3, b = 0.7;
  bool dashed = false;
  bool steps = false;  // piecewise constant: y[i] held from x[i] to x[i+1] (a bound that changes at keyframes)
  double width = 1.6;
};

enum class AxisScale { kLinear, kLog, kAuto };  // kAuto: log when the positive data span more than 20×

struct PlotSpec {
  std::string title, xlabel, ylabel;
  std::vector<double> x;
  std::vector<Series> series;
  std::vector<double> flagged;  // red vertical lines (e.g. frames that could not be certified)
  std::vector<double> unconverged;  // orange dashed vertical lines (frames whose solve did not converge)
  // Legend entries for the two kinds of marks, shown when there are such marks.
  std::string flagged_label = "not certified", unconverged_label = "not converged";
  std::vector<double> x_marks;  // thin dotted vertical lines (e.g. keyframe times)
  std::string note;             // a line of small print under the legend
  AxisScale y_scale = AxisScale::kLinear;
  int width_px = 900, height_px = 420;
};

// A line plot: axes with ticks and labels, title, a legend that wraps onto more rows
// when it does not fit on one, optional log y-axis.
void plot_series(const std::filesystem::path& png, const PlotSpec& spec);
// The same, linear y, no y label.
void plot_series(const std::filesystem::path& png, const std::string& title, const std::string& xlabel,
                 const std::vector<double>& x, const std::vector<Series>& series, const std::vector<double>& flagged = {},
                 int width_px = 900, int height_px = 420);

}  // namespace hsi::draw
