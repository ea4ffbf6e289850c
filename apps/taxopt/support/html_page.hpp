#pragma once
/// @file One self-contained HTML page of a run (`--html FILE`): a 3D view of the part,
/// the toolpath and the tool axes before and after (coloured by the rotary axes' angular
/// acceleration), markers where a check fired, the rotary plots with the machine's limits, the
/// summary and the run's header. The page needs no network and no server: three.js,
/// OrbitControls and dygraphs (Debian's libjs-three and libjs-dygraphs) are embedded as read at
/// write time.

#include <cstddef>
#include <string>

#include "taxopt/core/toolpath.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/job.hpp"

namespace taxopt {

/// Where Debian installs the page's libraries (libjs-three, libjs-dygraphs).
inline constexpr const char* kDefaultJavascriptDir = "/usr/share/javascript";

/// The libraries a page embeds, as read from disk.
struct HtmlAssets {
  std::string three_js, orbit_controls_js, dygraph_js, dygraph_css;
};

/// Reads three/three.min.js, three/examples/js/controls/OrbitControls.js,
/// dygraphs/dygraph.min.js and dygraphs/dygraph.min.css under `javascript_dir`.
/// @throws InputError naming the first file that is missing or empty (and the package that
/// installs it).
HtmlAssets load_html_assets(const std::string& javascript_dir = kDefaultJavascriptDir);

/// What a page may hold; beyond it the page is decimated and says so.
struct HtmlBudget {
  /// Triangles of the part drawn (vertex clustering on a grid, coarser until within it).
  std::size_t max_triangles = 60000;
  /// Points per plot curve, over all operations: each operation keeps every k-th point and,
  /// within each stride, the points of its largest omega and a before and after (peaks stay).
  std::size_t max_plot_points = 40000;
  /// Tool axes drawn (before and after each), over all operations: every N-th point.
  std::size_t max_axes = 3000;
  /// Markers drawn (points where a check fired); beyond it the first ones of each kind.
  std::size_t max_markers = 20000;
};

/// A part mesh within `max_triangles` by vertex clustering on a cubic grid (cells' vertices
/// merged to their mean, collapsed triangles dropped); the mesh itself when within it.
/// `cell_mm` receives the grid's cell (0 when not decimated).
TriangleMesh decimate_mesh(const TriangleMesh& mesh, std::size_t max_triangles,
                           double* cell_mm = nullptr);

/// The page. `part_mm`: the part as run_job checked it (mm, the CL file's frame), or null. Its
/// data come from `result` (rows, marks, findings, summaries), `toolpath` (the input axes and
/// the passes) and `machine` (ranges and limits); `options` and `run` fill the header.
std::string html_page(const JobResult& result, const Toolpath& toolpath, const Machine& machine,
                      const JobOptions& options, const RunInfo& run, const TriangleMesh* part_mm,
                      const HtmlAssets& assets, const HtmlBudget& budget = {});

}  // namespace taxopt
