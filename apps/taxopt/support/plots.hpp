#pragma once
/// @file SVG plots of a run (`--plots DIR`): the rotary angles, the synthetic omega and a
/// against the cumulative arc length, before and after, with the optimiser's key points (the
/// paper's figs. 20-23); and C-space maps of chosen contact points (fig. 10). Plain SVG 1.1,
/// no scripts, readable as rendered by rsvg-convert or a browser.

#include <string>
#include <utility>
#include <vector>

#include "taxopt/job.hpp"

namespace taxopt {

/// One line of a plot.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::string colour = "#1f5fbf";
  bool dashed = false;
};

/// A line plot.
struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  /// x of vertical marker lines (e.g. segment boundaries), with their legend label.
  std::vector<double> markers_x;
  std::string markers_label;
  /// Logarithmic y axis (values <= 0 are drawn at the bottom).
  bool log_y = false;
};

/// The plot as an SVG document (960 x 360 px). Long series are reduced to the minimum and
/// maximum per pixel column, so the file stays small and every peak stays visible.
std::string svg_line_plot(const LinePlot& plot);

/// A C-space map as an SVG document: the hemisphere of axes seen down the contact normal
/// (radius = tilt, angle = yaw from the feed direction T towards K), free and blocked cells
/// inside the deviation cone, the input and output axes marked.
std::string svg_cspace_map(const CSpaceMap& map, const std::string& title);

/// Every plot of a run: file name and SVG text. Per operation (numbered in order):
/// `opN-angles-a.svg`, `opN-angles-c.svg`, `opN-omega.svg`, `opN-accel.svg`, and
/// `opN-cspace-I.svg` for each C-space map (I the CL point's index in the operation).
std::vector<std::pair<std::string, std::string>> job_plots(const JobResult& result);

}  // namespace taxopt
