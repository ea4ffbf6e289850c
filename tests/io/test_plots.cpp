#include <catch2/catch.hpp>
#include <sstream>

#include "support.hpp"
#include "support/plots.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// The y coordinates of the points of the n-th polyline of an SVG.
std::vector<double> polyline_y(const std::string& svg, std::size_t nth) {
  std::size_t at = 0;
  for (std::size_t k = 0; k <= nth; ++k) at = svg.find("<polyline", at + 1);
  const std::size_t p = svg.find("points=\"", at) + 8;
  std::istringstream pts(svg.substr(p, svg.find('"', p) - p));
  std::vector<double> y;
  std::string xy;
  while (pts >> xy) y.push_back(std::stod(xy.substr(xy.find(',') + 1)));
  return y;
}

}  // namespace

TEST_CASE("plots: a line plot has its title, axis labels, legend and every series", "[plots]") {
  LinePlot p;
  p.title = "T & <title>";
  p.x_label = "arc length (mm)";
  p.y_label = "omega (deg/s)";
  p.series.push_back({"before", {0, 1, 2}, {1, 3, 2}, "#888888", true});
  p.series.push_back({"after", {0, 1, 2}, {1, 2, 1}, "#1f5fbf", false});
  p.markers_x = {1.0};
  p.markers_label = "segment boundaries";
  const std::string svg = svg_line_plot(p);
  CHECK_THAT(svg, Catch::StartsWith("<?xml"));
  CHECK_THAT(svg, Catch::EndsWith("</svg>\n"));
  CHECK_THAT(svg, Catch::Contains("T &amp; &lt;title&gt;"));  // escaped
  for (const char* text :
       {"arc length (mm)", "omega (deg/s)", ">before<", ">after<", ">segment boundaries<"}) {
    CHECK_THAT(svg, Catch::Contains(text));
  }
  CHECK(count_of(svg, "<polyline") == 2);
  CHECK(count_of(svg, "stroke-dasharray=\"5,3\" points=") == 1);
}

TEST_CASE("plots: a long series is reduced per pixel column and keeps its peak", "[plots]") {
  LinePlot p;
  PlotSeries s;
  for (int i = 0; i < 100000; ++i) {
    s.x.push_back(i * 0.01);
    s.y.push_back(i == 61234 ? 50.0 : 1.0 + 0.001 * (i % 7));
  }
  p.series.push_back(s);
  for (bool log_y : {false, true}) {
    p.log_y = log_y;
    const std::vector<double> y = polyline_y(svg_line_plot(p), 0);
    CHECK(y.size() <= 4 * 960);
    // The spike is the top of the drawing, far above the rest.
    const double top = *std::min_element(y.begin(), y.end());
    std::size_t near_top = 0;
    for (double v : y) near_top += v < top + 1.0 ? 1 : 0;
    CHECK(near_top >= 1);
    CHECK(near_top <= 4);
    CHECK(*std::max_element(y.begin(), y.end()) - top > 100.0);
  }
}

TEST_CASE("plots: --plots writes A, C, omega, a and the C-space maps -- blocked cells show",
          "[plots][cli]") {
  // A wall beside a flat path, axes leaning the shank into it (as in the wall acceptance
  // test): the map of the most constrained point must show blocked and free cells.
  const Heightfield hf = wall_heightfield();
  TempDir t;
  write_file(t.path("in.cls"), raster_cl(hf, 3.0, 0.0, 1, 1.0, 16.0, 16.0, 0.0, 20.0).text);
  write_file(t.path("part.stl"),
             format_stl_binary(heightfield_mesh(hf, 1.0, -20.0, 40.0, -10.0, 50.0)));
  const RunResult r = run_taxopt("--in " + t.path("in.cls") + " --part " + t.path("part.stl") +
                                 " --gcode " + t.path("o.nc") + " --plots " + t.path("plots") +
                                 " -q --holder-radius 14 --holder-length 30");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* f : {"op1-angles-a.svg", "op1-angles-c.svg", "op1-omega.svg", "op1-accel.svg"}) {
    INFO(f);
    const std::string svg = read_file(t.path("plots/") + f);
    CHECK(count_of(svg, "<polyline") == 2);
    CHECK_THAT(svg, Catch::Contains("arc length along the path (mm)"));
  }
  std::size_t maps = 0, blocked = 0;
  for (int i = 0; i < 40; ++i) {
    const std::string path = t.path("plots/op1-cspace-" + std::to_string(i) + ".svg");
    if (!file_exists(path)) continue;
    ++maps;
    const std::string svg = read_file(path);
    CHECK(count_of(svg, "fill=\"#bfe3b4\" stroke") > 0);  // free cells
    blocked += count_of(svg, "fill=\"#d9534f\" stroke");
    CHECK_THAT(svg, Catch::Contains("input axis (tilt"));
    CHECK_THAT(svg, Catch::Contains("output axis (tilt"));
  }
  CHECK(maps >= 1);
  CHECK(blocked > 0);
  // Without a part: the line plots only.
  const RunResult bare = run_taxopt("--in " + t.path("in.cls") + " --gcode " + t.path("b.nc") +
                                    " --plots " + t.path("bare") + " -q");
  REQUIRE(bare.code == 0);
  CHECK(file_exists(t.path("bare/op1-omega.svg")));
  CHECK_FALSE(file_exists(t.path("bare/op1-cspace-0.svg")));
}
