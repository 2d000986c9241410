// hsi compare, stage 3: the figures. The side-by-side panels (every method rendered with
// the texture and the conformal distortion colour map, one view and one colour range for
// all, Vulkan) and the plots over the sequence (distortion against the keyframes' bounds,
// time per frame, Fig. 8's distances), written as PNGs.
#pragma once

#include <string>
#include <vector>

#include "hsi/compare/outputs.h"
#include "hsi/compare/runs.h"
#include "hsi/png.h"
#include "hsi/scene_texture.h"
#include "hsi/draw/raster.h"

namespace hsi::compute {
class Context;
}

namespace hsi::compare {

// A side-by-side column: a rendered panel with its caption.
struct Column {
  std::string name, stats;
  bool stats_alarm = false;  // stats in red (a broken or folded result)
  RgbaImage image;
};
// The side-by-side figure: title, per column a name and a line of numbers, the panels
// (all of the first one's size), and one colour bar over [lo, hi] for all of them.
draw::Surface compose(const std::string& title, const std::vector<Column>& cols, double lo, double hi);

// The colour range's top: the largest κ any panel shows, but no further than the keyframes'
// bound (beyond it, values saturate: the eye sees where a method leaves it), rounded up.
double colour_range_hi(const std::vector<Snapshot>& snaps, bool boundary_metric);

struct SideBySide {
  int panel_width = 0, panel_height = 0;  // each panel, fitted to the frames' aspect
  double range_hi = 1;                    // the colour range is [1, range_hi]
};
// Renders and writes side_by_side_t0.25/0.50/0.75.png; sets each snapshot's png and size.
SideBySide side_by_side(compute::Context& ctx, const Inputs& in, const Baselines& b, std::vector<Snapshot>& snaps, int panel,
                        int segment, Outputs& out);

// What the plots name besides the per-frame numbers.
struct PlotLabels {
  std::string scene_name;
  std::vector<double> keyframe_times;  // dotted lines
  bool holes = false;                  // CCW16 (log derivatives) is then not a map
  bool boundary_metric = false;        // CCW16 (boundary metric) ran (simply connected)
  int boundary_metric_coarse_vertices = 0;  // > 0: it ran on a coarser mesh of this many vertices
  int mesh_vertices = 0;                    // the baselines' render mesh
  std::string core;                         // our Newton core
};
// kappa.png, isometric.png, frame_time.png and, where the boundary-metric variant ran,
// ccw16_distance.png (Fig. 8); returns how many plots it wrote.
int plots(const PerFrame& p, const PlotLabels& labels, Outputs& out);

}  // namespace hsi::compare
