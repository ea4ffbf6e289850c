// Contact recovery speed: points/s on a part of about 1M triangles, 1 and 2 threads.
// Run: build/release/bench/bench_contact [triangles] [points]
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/geometry/raster_generator.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"

using namespace taxopt;

namespace {

/// Rolling bumps: z = 6 sin(x / 9) cos(y / 11) over [0, 100]^2 (concave radii above 3 mm).
struct Bumps {
  double u_min() const { return 0.0; }
  double u_max() const { return 100.0; }
  double v_min() const { return 0.0; }
  double v_max() const { return 100.0; }
  SurfaceJet<double> jet(double u, double v) const {
    const double a = 6.0, p = 1.0 / 9.0, q = 1.0 / 11.0;
    const double su = std::sin(u * p), cu = std::cos(u * p), sv = std::sin(v * q),
                 cv = std::cos(v * q);
    SurfaceJet<double> j;
    j.p = Vec3d(u, v, a * su * cv);
    j.su = Vec3d(1, 0, a * p * cu * cv);
    j.sv = Vec3d(0, 1, -a * q * su * sv);
    j.suu = Vec3d(0, 0, -a * p * p * su * cv);
    j.suv = Vec3d(0, 0, -a * p * q * cu * sv);
    j.svv = Vec3d(0, 0, -a * q * q * su * cv);
    return j;
  }
};

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const long triangles = argc > 1 ? std::atol(argv[1]) : 1000000;
  const long points = argc > 2 ? std::atol(argv[2]) : 20000;
  const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(triangles) / 2.0)));
  const Bumps bumps;
  auto t0 = std::chrono::steady_clock::now();
  TriangleMesh mesh = tessellate(bumps, n, n);
  const double t_mesh = seconds(t0);
  const std::size_t faces = mesh.faces.size();
  t0 = std::chrono::steady_clock::now();
  const Part part(std::move(mesh));
  const double t_build = seconds(t0);

  // A raster path over the bumps, trimmed to the requested number of points.
  RasterOptions ro;
  ro.scallop_mm = 0.05;
  ro.chord_error_mm = 0.002;
  ro.max_step_mm = 0.3;
  const auto gen = generate_raster(bumps, ro);
  Operationd op;
  op.tool = Tool::ball_end_mill(6.0, 15.0);
  for (const auto& g : gen) {
    if (static_cast<long>(op.points.size()) >= points) break;
    CLPointd p;
    p.tip_mm = g.tip_mm;
    p.axis = g.axis;
    p.motion = g.rapid ? Motion::Rapid : Motion::Feed;
    op.points.push_back(p);
  }
  std::printf("# taxopt contact recovery benchmark\n");
  std::printf("# command: bench_contact %ld %ld\n", triangles, points);
  std::printf("# part: %zu triangles (tessellated in %.2f s), search structures built in %.2f s\n",
              faces, t_mesh, t_build);
  std::printf("| threads | CL points | touching | time s | points/s |\n|---|---|---|---|---|\n");
  for (int threads : {1, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism,
                           static_cast<std::size_t>(threads));
    t0 = std::chrono::steady_clock::now();
    const auto contacts = recover_contacts(part, op, 3.0);
    const double t = seconds(t0);
    std::size_t touching = 0;
    for (const auto& c : contacts) touching += c.state == ContactState::Touching ? 1 : 0;
    std::printf("| %d | %zu | %zu | %.3f | %.0f |\n", threads, op.points.size(), touching, t,
                static_cast<double>(op.points.size()) / t);
  }
  return 0;
}
