// The paper's method end to end on parts no code was tuned on (issue 5's "done when"): the
// CLI with its defaults on a sine-like part crossed by several passes and on a bump crossed
// off centre. Everything is judged independently of taxopt's own report: A and C as LinuxCNC's
// rs274 reads them from the G-code, the path lengths between the true contact points of the
// heightfield, the tool tested against every nearby mesh face with the exact
// triangle-versus-cylinder test (not FCL, which the optimiser uses).
#include <algorithm>
#include <catch2/catch.hpp>
#include <random>

#include "support.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/kinematics/ac_machine.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

struct Peaks {
  double omega_deg_s = 0.0, accel_deg_s2 = 0.0;
};

/// Peak synthetic omega and a of the paper's eq. 16-18 (eq. 18 corrected), per pass of
/// consecutive contact points, at feed v: omega_i = v (th_{i+1} - th_i) / L_i,
/// a_i = 2 v (omega_{i+1} - omega_i) / (L_i + L_{i+1}), per axis, then sqrt(A^2 + C^2).
Peaks peaks(const std::vector<CanonMove>& moves, const GeneratedCl& g, double feed_mm_s) {
  Peaks p;
  std::size_t i = 0;
  while (i < moves.size()) {
    if (g.rapid[i]) {
      ++i;
      continue;
    }
    std::size_t e = i;
    while (e < moves.size() && !g.rapid[e]) ++e;
    std::vector<double> wa, wc, len;
    for (std::size_t j = i; j + 1 < e; ++j) {
      const double l = (g.cc_mm[j + 1] - g.cc_mm[j]).norm();
      len.push_back(l);
      wa.push_back(feed_mm_s * (moves[j + 1].a - moves[j].a) / l);
      wc.push_back(feed_mm_s * (moves[j + 1].c - moves[j].c) / l);
      p.omega_deg_s = std::max(p.omega_deg_s, std::hypot(wa.back(), wc.back()));
    }
    for (std::size_t j = 0; j + 1 < wa.size(); ++j) {
      const double s = len[j] + len[j + 1];
      const double aa = 2.0 * feed_mm_s * (wa[j + 1] - wa[j]) / s;
      const double ac = 2.0 * feed_mm_s * (wc[j + 1] - wc[j]) / s;
      p.accel_deg_s2 = std::max(p.accel_deg_s2, std::hypot(aa, ac));
    }
    i = e;
  }
  return p;
}

/// A mesh face's bounding sphere, in plain doubles: the prefilter below runs for every face
/// and point, and Eigen's expression templates are slow in a Debug build.
struct FaceSphere {
  double x, y, z, r;
};

std::vector<FaceSphere> face_spheres(const TriangleMesh& mesh) {
  std::vector<FaceSphere> out;
  for (const auto& f : mesh.faces) {
    const Vec3d& a = mesh.vertices[f[0]];
    const Vec3d& b = mesh.vertices[f[1]];
    const Vec3d& d = mesh.vertices[f[2]];
    const Vec3d mid = (a + b + d) / 3.0;
    const double r = std::max({(a - mid).norm(), (b - mid).norm(), (d - mid).norm()});
    out.push_back({mid.x(), mid.y(), mid.z(), r});
  }
  return out;
}

/// True when some body of the tool at ball centre `c` and axis `v` meets a face of the mesh.
/// Exact test (triangle_meets_cylinder) on the faces whose bounding sphere reaches the
/// body's segment; the others cannot meet it.
bool tool_hits(const TriangleMesh& mesh, const std::vector<FaceSphere>& spheres,
               const ToolModel& tool, const Vec3d& c, const Vec3d& v) {
  for (std::size_t k = 0; k < spheres.size(); ++k) {
    const FaceSphere& f = spheres[k];
    const double px = f.x - c.x(), py = f.y - c.y(), pz = f.z - c.z();
    const double along = px * v.x() + py * v.y() + pz * v.z();
    for (const ToolBody& body : tool.bodies) {
      const double t = std::clamp(along, body.start_mm, body.end_mm);
      const double qx = px - t * v.x(), qy = py - t * v.y(), qz = pz - t * v.z();
      const double reach = body.radius_mm + f.r;
      if (qx * qx + qy * qy + qz * qz > reach * reach) continue;
      const auto& face = mesh.faces[k];
      if (triangle_meets_cylinder(mesh.vertices[face[0]], mesh.vertices[face[1]],
                                  mesh.vertices[face[2]], c, v, body.radius_mm, body.start_mm,
                                  body.end_mm)) {
        return true;
      }
    }
  }
  return false;
}

struct Case {
  std::string name;
  Heightfield hf;
  GeneratedCl cl;
};

void check_case(const Case& k) {
  INFO(k.name);
  TempDir dir;
  write_file(dir.path("in.cls"), k.cl.text);
  const TriangleMesh mesh = heightfield_mesh(k.hf, 0.5, -10.0, 70.0, -10.0, 70.0);
  write_file(dir.path("part.stl"), format_stl_binary(mesh));
  const std::string common = "--in " + dir.path("in.cls") + " --part " + dir.path("part.stl");
  // Before: the input axes as posted (--force: an input that collides still gives its G-code).
  const RunResult before_run =
      run_taxopt(common + " --method none --force -q --gcode " + dir.path("before.ngc"));
  INFO("before: exit " << before_run.code << " " << before_run.err);
  REQUIRE((before_run.code == 0 || before_run.code == 1));
  // After: the defaults (--method paper, --max-deviation 30, --grid 2).
  const RunResult after_run = run_taxopt(common + " -q --gcode " + dir.path("after.ngc") +
                                         " --out-cls " + dir.path("out.cls"));
  INFO(after_run.err);
  REQUIRE(after_run.code == 0);

  std::vector<CanonMove> before, after;
  REQUIRE(run_rs274(dir.path("before.ngc"), before).code == 0);
  REQUIRE(run_rs274(dir.path("after.ngc"), after).code == 0);
  REQUIRE(before.size() == k.cl.tips_mm.size());
  REQUIRE(after.size() == k.cl.tips_mm.size());

  const double v = 250.0 / 60.0;  // FEDRAT/MMPM,250 of the generated file, mm/s
  const Peaks pb = peaks(before, k.cl, v), pa = peaks(after, k.cl, v);
  INFO("peak omega " << pb.omega_deg_s << " -> " << pa.omega_deg_s << " deg/s, peak a "
                     << pb.accel_deg_s2 << " -> " << pa.accel_deg_s2 << " deg/s^2");
  CHECK(pa.omega_deg_s <= (1.0 - 0.109) * pb.omega_deg_s);
  CHECK(pa.accel_deg_s2 <= (1.0 - 0.248) * pb.accel_deg_s2);

  const ACMachined machine = default_ac_machine();
  const ToolModel tool = ToolModel::ball_end(Tool::ball_end_mill(6.0, 30.0));
  double worst_centre = 0.0, worst_dev = 0.0;
  std::size_t hits = 0;
  const std::vector<FaceSphere> spheres = face_spheres(mesh);
  for (std::size_t i = 0; i < after.size(); ++i) {
    const CanonMove& m = after[i];
    const Vec3d axis = machine.forward(Posed{deg_to_rad(m.a), deg_to_rad(m.c)});
    const Vec3d centre = Vec3d(m.x, m.y, m.z) + 3.0 * axis;
    worst_centre = std::max(worst_centre, (centre - k.cl.centres_mm[i]).norm());
    worst_dev = std::max(worst_dev, rad_to_deg(angle_between(axis, k.cl.axes[i])));
    if (!k.cl.rapid[i] && tool_hits(mesh, spheres, tool, centre, axis)) ++hits;
  }
  INFO("ball centres moved up to " << worst_centre << " mm, axes up to " << worst_dev << " deg");
  CHECK(worst_centre <= 0.005);
  CHECK(worst_dev <= 30.0 + 0.01);
  CHECK(hits == 0);
}

}  // namespace

// Issue 5's acceptance target. Near the pole A = 0 the paper's slerp alone is not enough (on
// the sine-like part the passes graze the pole and C turns fast: 728 -> 683 deg/s, -6 %);
// the pole passages re-planned in machine space (plan/pole_passage.hpp) are what meets it.
TEST_CASE(
    "paper method: on unseen sine-like and bump parts the peaks fall by the paper's "
    "margins, safely",
    "[paper-done-when][integration]") {
  REQUIRE(have_rs274());
  std::mt19937 rng(9001);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Case> cases;
  {
    // A sine-like part (its concave radius stays above 4 mm), four passes across it.
    const double h = 5.0 + 4.0 * u(rng), lambda = 38.0 + 15.0 * u(rng), ph = 6.28 * u(rng);
    const double wobble = 0.1 * u(rng);
    Heightfield hf;
    hf.name = "sine-like";
    hf.z = [=](double x, double y) {
      return h * std::sin(2.0 * Constants<double>::pi() * x / lambda + ph) *
             (1.0 + wobble * std::sin(y / 7.0));
    };
    hf.normal = [z = hf.z](double x, double y) {
      const double e = 1e-5;
      return Vec3d(-(z(x + e, y) - z(x - e, y)) / (2 * e), -(z(x, y + e) - z(x, y - e)) / (2 * e),
                   1.0)
          .normalized();
    };
    cases.push_back({"sine-like", hf, raster_cl(hf, 3.0, 5.0, 4, 0.5, 15.0, 35.0, 0.0, 60.0)});
  }
  {
    // A bump crossed off centre: three passes between 0.3 and 0.6 of its width beside the top.
    std::mt19937 shape_rng(static_cast<unsigned>(1 + 1000 * u(rng)));
    const Heightfield hf = random_heightfields(shape_rng)[1];
    double top_x = 0.0, top_y = 0.0, top_z = -1e9;
    for (double x = 10; x <= 40; x += 0.25) {
      for (double y = 10; y <= 40; y += 0.25) {
        if (hf.z(x, y) > top_z) top_z = hf.z(x, y), top_x = x, top_y = y;
      }
    }
    (void)top_x;
    const double off = 2.5 + 2.0 * u(rng);
    cases.push_back(
        {"bump", hf, raster_cl(hf, 3.0, 5.0, 3, 0.5, top_y + off, top_y + off + 2.0, 0.0, 50.0)});
  }
  for (const Case& k : cases) check_case(k);
}
