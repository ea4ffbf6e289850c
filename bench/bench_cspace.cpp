// C-space rasteriser versus brute force (one FCL query per cell), side by side.
// Run: build/release/bench/bench_cspace [points] [brute-force points] [demo|big|all]
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "taxopt/cspace/cspace.hpp"
#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt;

namespace {

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Case {
  std::string name;
  TriangleMesh mesh;
  SineSurfaced surface;
};

void run(const Case& c, const ToolModel& tool, double cell_deg, long points, long brute_points) {
  const Part part(c.mesh);
  const CollisionModel fcl(c.mesh);
  auto t_build = std::chrono::steady_clock::now();
  const CSpaceRasteriser rast(c.mesh);
  const double build_s = seconds(t_build);
  RasterOptions ro;
  const auto gen = generate_raster(c.surface, ro);
  Operationd op;
  op.tool = Tool::ball_end_mill(6.0, 15.0);
  for (const auto& g : gen) {
    if (g.rapid) continue;
    CLPointd p;
    p.tip_mm = g.tip_mm;
    p.axis = g.axis;
    op.points.push_back(p);
  }
  // Spread the sample over the whole path.
  Operationd sample = op;
  sample.points.clear();
  const std::size_t stride =
      std::max<std::size_t>(1, op.points.size() / static_cast<std::size_t>(points));
  for (std::size_t i = 0; i < op.points.size() && static_cast<long>(sample.points.size()) < points;
       i += stride) {
    sample.points.push_back(op.points[i]);
  }
  const auto contacts = recover_contacts(part, sample, 3.0);
  CSpaceOptions opt;
  opt.cell_deg = cell_deg;
  opt.max_deviation_deg = 30.0;
  const std::size_t n = sample.points.size();
  const auto centre = [&](std::size_t i) {
    return sample.points[i].tip_mm + 3.0 * sample.points[i].axis;
  };
  double fast_rate[3] = {0, 0, 0}, brute_rate = 0.0;
  for (int threads : {1, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism,
                           static_cast<std::size_t>(threads));
    auto t0 = std::chrono::steady_clock::now();
    std::vector<std::size_t> free_cells(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      free_cells[i] =
          rast.free_axes(tool, contacts[i], centre(i), sample.points[i].axis, opt).free_count();
    });
    const double t_fast = seconds(t0);
    fast_rate[threads] = static_cast<double>(n) / t_fast;
    std::printf(
        "| %s | %zu | %.0f | rasteriser (tree built in %.2f s) | %d | %zu | %.3f | %.1f |\n",
        c.name.c_str(), c.mesh.faces.size(), cell_deg, build_s, threads, n, t_fast,
        fast_rate[threads]);
    if (threads == 1) {
      const std::size_t nb = std::min<std::size_t>(n, static_cast<std::size_t>(brute_points));
      t0 = std::chrono::steady_clock::now();
      std::size_t mismatch = 0;
      double t_brute_only = 0.0;
      for (std::size_t s = 0; s < nb; ++s) {
        const std::size_t i = s * n / nb;  // spread over the path
        const CSpaceGrid b =
            brute_force_free_axes(fcl, tool, contacts[i], centre(i), sample.points[i].axis, opt);
        t_brute_only += seconds(t0);
        const CSpaceGrid f =
            rast.free_axes(tool, contacts[i], centre(i), sample.points[i].axis, opt);
        t0 = std::chrono::steady_clock::now();
        for (int a = 0; a < b.tilt_cells(); ++a) {
          for (int y = 0; y < b.yaw_cells(); ++y) mismatch += b.free(a, y) != f.free(a, y) ? 1 : 0;
        }
      }
      const double t_brute = t_brute_only;
      std::printf(
          "| %s | %zu | %.0f | brute force (FCL per cell) | 1 | %zu | %.3f | %.1f |  mismatching "
          "cells: %zu\n",
          c.name.c_str(), c.mesh.faces.size(), cell_deg, nb, t_brute,
          static_cast<double>(nb) / t_brute, mismatch);
      brute_rate = static_cast<double>(nb) / t_brute;
    }
  }
  std::printf(
      "| %s | %zu | %.0f | speed-up over brute force, 1 thread: %.1fx; 2 threads: %.1fx; "
      "10,000 points on 2 threads: %.1f s |\n",
      c.name.c_str(), c.mesh.faces.size(), cell_deg, fast_rate[1] / brute_rate,
      fast_rate[2] / brute_rate, 10000.0 / fast_rate[2]);
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const long points = argc > 1 ? std::atol(argv[1]) : 200;
  const long brute = argc > 2 ? std::atol(argv[2]) : 5;
  const std::string which = argc > 3 ? argv[3] : "all";
  const Tool t = Tool::ball_end_mill(6.0, 15.0);
  ToolOverrides o;
  o.gauge_length_mm = 60.0;
  o.holder_radius_mm = 16.0;
  o.holder_length_mm = 40.0;
  const ToolModel tool = ToolModel::ball_end(t, o);
  std::printf(
      "# taxopt C-space benchmark: tool R3 flutes 15, shank to 60, holder r16 x 40; window 30 "
      "deg\n");
  std::printf("# command: bench_cspace %ld %ld %s\n", points, brute, which.c_str());
  std::printf(
      "| part | triangles | cell deg | method | threads | points | time s | points/s "
      "|\n|---|---|---|---|---|---|---|---|\n");
  std::vector<Case> cases;
  SineSurfaced demo;
  SineSurfaced big = demo;
  big.x0_mm = -12, big.x1_mm = 32, big.y0_mm = -12, big.y1_mm = 92;
  if (which != "big") cases.push_back({"demo sine (0.5 mm mesh)", tessellate(big, 88, 208), demo});
  if (which != "demo") cases.push_back({"sine, 500k triangles", tessellate(big, 340, 736), demo});
  for (const auto& c : cases) {
    for (double cell : {2.0, 1.0}) run(c, tool, cell, points, brute);
  }
  return 0;
}
