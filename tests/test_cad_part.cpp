// Every block of the program outside the part, judged by a sweep written here: a CAD-style part
// (a floor, a concave fillet up to a wall, a lip over the fillet: an undercut reached with a
// tool tilted 45 deg), posted by every method in every dialect and in machine mode. The sweep
// reads the program back, moves the tool along each block as the controller does (the tip on a
// straight line and A, C linear under TCP; the joints linear in machine mode) and measures the
// ball and the shank against every triangle of the mesh (brute force: no FCL, no CGAL, none of
// taxopt's checks).
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>

#include "support.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kBallR = 3.0, kFilletR = 6.0;

/// The profile in xz (extruded over y in [-25, 25]): a floor at z = 0 up to x = 0, a concave
/// fillet of radius 6 (12 chords) up to the wall at x = 6, the wall up to z = 16, a lip back
/// over the fillet to x = -4 between z = 16 and z = 20, its top out to x = 16, the right side,
/// the bottom. One quad per segment over the whole length, as CAD systems export.
TriangleMesh lip_part() {
  std::vector<Eigen::Vector2d> p;
  p.emplace_back(-40.0, 0.0);
  for (int k = 0; k <= 12; ++k) {
    const double t = 0.5 * M_PI * k / 12;
    p.emplace_back(kFilletR * std::sin(t), kFilletR - kFilletR * std::cos(t));
  }
  for (const auto& q : std::vector<Eigen::Vector2d>{
           {6.0, 16.0}, {-4.0, 16.0}, {-4.0, 20.0}, {16.0, 20.0}, {16.0, -10.0}, {-40.0, -10.0}}) {
    p.push_back(q);
  }
  return extruded_profile(p, -25.0, 25.0, 1);
}

/// Raster passes along y on the floor and on the fillet, the tool tilted 45 deg away from the
/// wall (its shank under the lip's edge), each from a rapid 20 mm up its axis and back.
std::string lip_cl() {
  const Vec3d axis(-std::sin(45.0 * kDeg), 0.0, std::cos(45.0 * kDeg));
  std::vector<Vec3d> centres_at_y0;  // ball centres of each pass at y = 0
  for (double x : {-16.0, -10.0, -4.0}) centres_at_y0.emplace_back(x, 0.0, kBallR);
  for (double t : {15.0, 35.0}) {
    const double d = kFilletR - kBallR;  // centre to the fillet's axis
    centres_at_y0.emplace_back(d * std::sin(t * kDeg), 0.0, kFilletR - d * std::cos(t * kDeg));
  }
  std::ostringstream os;
  os.precision(10);
  os << "PARTNO/LIP\nUNITS/MM\nLOADTL/1\nCUTTER/6.0,3.0\nSPINDL/8000\nFEDRAT/800\n";
  const auto go = [&](const Vec3d& tip) {
    os << "GOTO/" << tip.x() << "," << tip.y() << "," << tip.z() << "," << axis.x() << ","
       << axis.y() << "," << axis.z() << "\n";
  };
  for (std::size_t k = 0; k < centres_at_y0.size(); ++k) {
    const double y0 = k % 2 ? 20.0 : -20.0, dy = k % 2 ? -1.0 : 1.0;
    const Vec3d first = centres_at_y0[k] + Vec3d(0.0, y0, 0.0) - kBallR * axis;
    os << "RAPID\n";
    go(first + 20.0 * axis);
    go(first);
    for (int j = 1; j <= 40; ++j) go(first + Vec3d(0.0, dy * j, 0.0));
    os << "RAPID\n";
    go(first + Vec3d(0.0, dy * 40, 0.0) + 20.0 * axis);
  }
  os << "FINI\n";
  return os.str();
}

/// Distance of p from the mesh (brute force).
double distance_to(const TriangleMesh& mesh, const Vec3d& p) {
  return (brute_nearest(mesh, p) - p).norm();
}

struct Sweep {
  std::size_t blocks = 0, samples = 0;
  double least_ball_gap_mm = 1e9, least_shank_gap_mm = 1e9;
  int worst_ball_line = 0, worst_shank_line = 0;
};

/// The tool along every block read back whose start and end are known in the workpiece: the
/// ball (its centre R from the tip) and the shank (the axis from the centre to 40 mm above it,
/// radius R), sampled every 0.25 mm of tip path or 0.5 deg of turn.
Sweep sweep(const std::vector<GcodeMove>& moves, const Machine& machine, const TriangleMesh& mesh) {
  Sweep s;
  const bool tcp = machine.gcode.mode == GcodeMode::Tcp;
  for (std::size_t i = 1; i < moves.size(); ++i) {
    const GcodeMove& a = moves[i - 1];
    const GcodeMove& b = moves[i];
    if (a.positioning || b.positioning) continue;  // after a retract: not known in the part
    REQUIRE_FALSE(b.arc);
    ++s.blocks;
    const Posed pa{a.tilt_deg * kDeg, a.c_deg * kDeg}, pb{b.tilt_deg * kDeg, b.c_deg * kDeg};
    const Vec3d tip_a = tip_of_written_mm(machine, a.xyz_mm, pa);
    const Vec3d tip_b = tip_of_written_mm(machine, b.xyz_mm, pb);
    const int n =
        1 + static_cast<int>(std::max(
                (tip_b - tip_a).norm() / 0.25,
                std::max(std::abs(b.tilt_deg - a.tilt_deg), std::abs(b.c_deg - a.c_deg)) / 0.5));
    for (int k = 0; k <= n; ++k) {
      const double u = static_cast<double>(k) / n;
      const Posed pose{pa.tilt_rad + u * (pb.tilt_rad - pa.tilt_rad),
                       pa.c_rad + u * (pb.c_rad - pa.c_rad)};
      // TCP: the tip on the line; machine mode: the joints on theirs.
      const Vec3d tip =
          tcp ? Vec3d(tip_a + u * (tip_b - tip_a))
              : tip_of_written_mm(machine, a.xyz_mm + u * (b.xyz_mm - a.xyz_mm), pose);
      const Vec3d axis = machine.rotary.forward(pose);
      const Vec3d centre = tip + kBallR * axis;
      ++s.samples;
      const double ball = distance_to(mesh, centre) - kBallR;
      if (ball < s.least_ball_gap_mm) s.least_ball_gap_mm = ball, s.worst_ball_line = b.line;
      for (double h = 2.0; h <= 40.0; h += 2.0) {
        const double shank = distance_to(mesh, centre + h * axis) - kBallR;
        if (shank < s.least_shank_gap_mm) s.least_shank_gap_mm = shank, s.worst_shank_line = b.line;
      }
    }
  }
  return s;
}

}  // namespace

TEST_CASE(
    "cad part: a floor, a fillet and an undercut reached with a tilted tool post with no block of "
    "the program inside the part, by every method, in every dialect and in machine mode, judged "
    "by a sweep of the program read back written here",
    "[pipeline][safety][cad][slow]") {
  const TriangleMesh mesh = lip_part();
  const Part part(mesh);
  const Toolpath tp = parse_cl(lip_cl(), "lip.cls");
  struct Case {
    const char* name;
    GcodeDialect dialect;
    GcodeMode mode;
  };
  const Case cases[] = {{"linuxcnc", GcodeDialect::LinuxCNC, GcodeMode::Tcp},
                        {"fanuc", GcodeDialect::Fanuc, GcodeMode::Tcp},
                        {"haas", GcodeDialect::Haas, GcodeMode::Tcp},
                        {"siemens", GcodeDialect::Siemens, GcodeMode::Tcp},
                        {"heidenhain", GcodeDialect::Heidenhain, GcodeMode::Tcp},
                        {"linuxcnc machine mode", GcodeDialect::LinuxCNC, GcodeMode::Machine}};
  for (const Case& c : cases) {
    for (Method method : {Method::None, Method::Paper, Method::Global}) {
      INFO(c.name << ", method " << static_cast<int>(method));
      Machine machine = default_machine();
      machine.gcode.dialect = c.dialect;
      machine.gcode.mode = c.mode;
      JobOptions options;
      options.part = &part;
      options.method = method;
      const JobResult r = run_job(tp, machine, options);
      for (const std::string& p : r.problems) UNSCOPED_INFO(p);
      REQUIRE(r.ok());
      long swept = 0;
      for (const OperationResult& o : r.operations) {
        CHECK(o.verification.colliding_blocks == 0);
        swept += o.verification.blocks_swept.value();
      }
      CHECK(swept > 0);
      check_blocks(r.gcode, c.dialect, machine.rotary.tilt_letter());
      const std::vector<GcodeMove> moves =
          read_gcode_moves(r.gcode.text, "lip.nc", c.dialect, r.gcode.verbatim_lines,
                           machine.rotary.tilt_letter(), r.gcode.tool_calls);
      const Sweep s = sweep(moves, machine, mesh);
      INFO("blocks " << s.blocks << ", samples " << s.samples << "; least ball gap "
                     << s.least_ball_gap_mm << " mm at G-code line " << s.worst_ball_line
                     << ", least shank gap " << s.least_shank_gap_mm << " mm at line "
                     << s.worst_shank_line);
      CHECK(s.blocks > 200);
      // The ball touches what it cuts within the part's tolerance (its chords sink 0.013 mm
      // into the fillet's mesh); the shank keeps off the lip, the wall and the floor.
      CHECK(s.least_ball_gap_mm >= -0.05);
      CHECK(s.least_shank_gap_mm >= 0.0);
      // A cut that never touched would prove nothing.
      CHECK(s.least_ball_gap_mm <= 0.02);
    }
  }
}
