// The real-job harness's part and CL file (real_job.hpp).
#include "real_job.hpp"

#include <cmath>
#include <functional>
#include <sstream>
#include <vector>

#include "support.hpp"

namespace taxopt::test {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kBallR = kRealJobBallMm;
constexpr double kFluteMm = kRealJobFluteMm;
/// The fillet at the boss's foot: its centre in (r, z) and radius.
constexpr double kFilletR = 5.0, kFilletCentreR = 19.0, kFilletCentreZ = 5.0;
/// The cone round the floor: from (r, z) = (50, 0) down to (70, -12).
constexpr double kConeR0 = 50.0, kConeR1 = 70.0, kConeDrop = 12.0;

/// A closed profile in the (r, z) half plane revolved about Z in `sectors` sectors: a ring of
/// quads per profile segment, a fan where a segment ends on the axis (r = 0).
TriangleMesh revolved_profile(const std::vector<Eigen::Vector2d>& rz, int sectors) {
  TriangleMesh m;
  std::vector<std::vector<int>> ids(rz.size());
  for (std::size_t i = 0; i < rz.size(); ++i) {
    const int n = rz[i].x() == 0.0 ? 1 : sectors;
    for (int s = 0; s < n; ++s) {
      const double phi = 2.0 * M_PI * s / sectors;
      ids[i].push_back(static_cast<int>(m.vertices.size()));
      m.vertices.emplace_back(rz[i].x() * std::cos(phi), rz[i].x() * std::sin(phi), rz[i].y());
    }
  }
  const auto at = [&](std::size_t i, int s) {
    return ids[i][ids[i].size() == 1 ? 0 : s % sectors];
  };
  for (std::size_t i = 0; i < rz.size(); ++i) {
    const std::size_t j = (i + 1) % rz.size();
    if (ids[i].size() == 1 && ids[j].size() == 1) continue;
    for (int s = 0; s < sectors; ++s) {
      if (ids[i].size() > 1) m.faces.push_back({at(i, s), at(i, s + 1), at(j, s)});
      if (ids[j].size() > 1) m.faces.push_back({at(i, s + 1), at(j, s + 1), at(j, s)});
    }
  }
  return m;
}

/// The oval boss: the wall's foot is the ellipse of half-axes kOvalA x kOvalB about kOvalCentre
/// (at z = 0, where the wall's plane would meet the floor); the wall overhangs the fillet at its
/// foot by kUndercutDeg (an undercut: a tool leaning out less than that reaches into it).
constexpr double kOvalA = 16.0, kOvalB = 10.0, kUndercutDeg = 12.0;
const Vec3d kOvalCentre(0.0, -140.0, 0.0);

/// A closed convex curve in a plane z = const about `centre`: its point and outward normal at
/// u in [0, 1) (once round, anticlockwise); a profile in (d, z) swept along it (d: the offset
/// along the normal) makes a part, a path offset from it a loop round that part.
struct Loop {
  Vec3d centre;
  std::function<Vec3d(double)> point, normal;
  Vec3d at(double u, double d, double z) const {
    return point(u) + d * normal(u) + Vec3d(0.0, 0.0, z);
  }
  Vec3d tangent(double u) const { return Vec3d::UnitZ().cross(normal(u)); }
};

/// The oval boss's foot.
Loop oval_loop() {
  Loop l;
  l.centre = kOvalCentre;
  l.point = [](double u) -> Vec3d {
    return kOvalCentre + Vec3d(kOvalA * std::cos(2 * M_PI * u), kOvalB * std::sin(2 * M_PI * u), 0);
  };
  l.normal = [](double u) -> Vec3d {
    return Vec3d(kOvalB * std::cos(2 * M_PI * u), kOvalA * std::sin(2 * M_PI * u), 0).normalized();
  };
  return l;
}

/// A rectangle of half-sides hx, hy with corners of radius r, by arc length.
Loop rounded_rectangle(const Vec3d& centre, double hx, double hy, double r) {
  const double sx = 2 * (hx - r), sy = 2 * (hy - r), arc = 0.5 * M_PI * r;
  const double length = 2 * sx + 2 * sy + 4 * arc;
  // Where arc length s lies: on side k (0: +x side going up, then anticlockwise) or the corner
  // after it; the corner's centre and the normal there.
  const auto place = [=](double u, Vec3d& p, Vec3d& n) {
    double s = u * length;
    const double side[4] = {sy, sx, sy, sx};
    const Vec3d corner[4] = {{hx - r, hy - r, 0},
                             {-(hx - r), hy - r, 0},
                             {-(hx - r), -(hy - r), 0},
                             {hx - r, -(hy - r), 0}};
    for (int k = 0; k < 4; ++k) {
      const double a0 = 0.5 * M_PI * k;  // the normal's angle along side k
      const Vec3d nk(std::cos(a0), std::sin(a0), 0), tk(-std::sin(a0), std::cos(a0), 0);
      if (s <= side[k]) {
        n = nk;
        p = centre + corner[(k + 3) % 4] + r * nk + s * tk;
        return;
      }
      s -= side[k];
      if (s <= arc || k == 3) {
        const double a = a0 + std::min(s, arc) / r;
        n = Vec3d(std::cos(a), std::sin(a), 0);
        p = centre + corner[k] + r * n;
        return;
      }
      s -= arc;
    }
  };
  Loop l;
  l.centre = centre;
  l.point = [place](double u) -> Vec3d {
    Vec3d p, n;
    place(u, p, n);
    return p;
  };
  l.normal = [place](double u) -> Vec3d {
    Vec3d p, n;
    place(u, p, n);
    return n;
  };
  return l;
}

/// The block with a chamfer round its top edge: its wall.
Loop block_loop() { return rounded_rectangle(Vec3d(140.0, 0.0, 0.0), 20.0, 14.0, 8.0); }

/// The oval boss's fillet (radius 5) between the floor and the undercut wall, in (d, z): its
/// centre.
Eigen::Vector2d undercut_fillet_centre() {
  const double w = kUndercutDeg * kDeg;
  return {kFilletR / std::cos(w) + kFilletR * std::tan(w), kFilletR};
}

/// A profile in (d, z) swept round a loop (`samples` sectors), its first and last points
/// joined to the loop's centre at their heights by fans.
TriangleMesh swept(const Loop& loop, const std::vector<Eigen::Vector2d>& dz, int samples) {
  TriangleMesh m;
  const int n = static_cast<int>(dz.size());
  for (int s = 0; s < samples; ++s) {
    const double u = static_cast<double>(s) / samples;
    for (const auto& q : dz) m.vertices.push_back(loop.at(u, q.x(), q.y()));
  }
  const auto id = [&](int s, int i) { return (s % samples) * n + i; };
  for (int s = 0; s < samples; ++s) {
    for (int i = 0; i + 1 < n; ++i) {
      m.faces.push_back({id(s, i), id(s + 1, i), id(s + 1, i + 1)});
      m.faces.push_back({id(s, i), id(s + 1, i + 1), id(s, i + 1)});
    }
  }
  for (int end : {0, n - 1}) {
    const int centre = static_cast<int>(m.vertices.size());
    m.vertices.push_back(loop.centre + Vec3d(0.0, 0.0, dz[end].y()));
    for (int s = 0; s < samples; ++s) {
      if (end == 0) {
        m.faces.push_back({centre, id(s + 1, end), id(s, end)});
      } else {
        m.faces.push_back({centre, id(s, end), id(s + 1, end)});
      }
    }
  }
  return m;
}

/// The oval boss (20 high, its wall leaning out over its fillet) on a plate 30 mm wider.
TriangleMesh oval_boss() {
  const double w = kUndercutDeg * kDeg;
  const Eigen::Vector2d f = undercut_fillet_centre();
  std::vector<Eigen::Vector2d> dz{{20.0 * std::tan(w), 20.0}};
  for (int k = 24; k >= 0; --k) {  // the fillet from the wall (beta = 90 + w) to the floor
    const double beta = (90.0 + kUndercutDeg) * kDeg * k / 24;
    dz.emplace_back(f.x() - kFilletR * std::sin(beta), f.y() - kFilletR * std::cos(beta));
  }
  dz.emplace_back(30.0, 0.0);
  dz.emplace_back(30.0, -20.0);
  return swept(oval_loop(), dz, 360);
}

/// Six times the signed volume a closed mesh holds (positive: outward normals).
double signed_volume6(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& f : m.faces) {
    v += m.vertices[f[0]].dot(m.vertices[f[1]].cross(m.vertices[f[2]]));
  }
  return v;
}

/// The meshes of one part put together (their faces outward).
void append(TriangleMesh& to, TriangleMesh from) {
  if (signed_volume6(from) < 0.0) {
    for (auto& f : from.faces) std::swap(f[1], f[2]);
  }
  const int base = static_cast<int>(to.vertices.size());
  to.vertices.insert(to.vertices.end(), from.vertices.begin(), from.vertices.end());
  for (const auto& f : from.faces) to.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
}

/// A CL file being written: NX CLSF operations of ball centres and axes, each pass from a rapid
/// 20 mm up its first axis, plunging, and back up its last.
struct JobCl {
  std::ostringstream os;
  JobCl() {
    os.precision(10);
    os << "$$ taxopt's real-job harness (tests/test_real_job.cpp)\nUNITS/MM\n";
  }
  void go(const Vec3d& tip, const Vec3d& axis) {
    os << "GOTO/" << tip.x() << "," << tip.y() << "," << tip.z() << "," << axis.x() << ","
       << axis.y() << "," << axis.z() << "\n";
  }
  void operation(const std::string& name) {
    os << "TOOL PATH/" << name << ",TOOL,BALL6\nTLDATA/MILL,6.0,3.0," << kFluteMm
       << ",0.0,0.0\nLOADTL/1\nSPINDL/8000\nFEDRAT/800\n";
  }
  void pass(const std::vector<Vec3d>& centres, const std::vector<Vec3d>& axes) {
    os << "RAPID\n";
    go(centres.front() - kBallR * axes.front() + 20.0 * axes.front(), axes.front());
    for (std::size_t i = 0; i < centres.size(); ++i) go(centres[i] - kBallR * axes[i], axes[i]);
    os << "RAPID\n";
    go(centres.back() - kBallR * axes.back() + 20.0 * axes.back(), axes.back());
  }
  void end() { os << "END-OF-PATH\n"; }
};

Vec3d radial(double phi) { return Vec3d(std::cos(phi), std::sin(phi), 0.0); }
/// The direction at polar angle `polar` from +Z toward the radial direction at `phi`.
Vec3d leaning(double polar, double phi) {
  return std::cos(polar) * Vec3d::UnitZ() + std::sin(polar) * radial(phi);
}

void chamfer(JobCl& cl) {
  const Vec3d n = Vec3d(-1.0, 0.0, 1.0).normalized();
  const Vec3d axis = (n + std::tan(10.0 * kDeg) * Vec3d::UnitY()).normalized();
  cl.operation("CHAMFER");
  for (double x : {-148.0, -146.0}) {  // a third and two thirds up the chamfer
    std::vector<Vec3d> c, a;
    for (int k = -35; k <= 35; ++k) {
      c.push_back(Vec3d(x, k, x + 164.0) + kBallR * n);
      a.push_back(axis);
    }
    cl.pass(c, a);
  }
  cl.end();
}

/// Round the block's chamfer at a 10 deg lead: C turns a quarter round each corner, and stands
/// between them.
void outline_chamfer(JobCl& cl) {
  const Loop block = block_loop();
  cl.operation("OUTLINE_CHAMFER");
  std::vector<Vec3d> c, a;
  for (int k = 0; k <= 240; ++k) {
    const double u = k / 240.0;
    const Vec3d n = (block.normal(u) + Vec3d::UnitZ()).normalized();
    c.push_back(block.at(u, -3.0, 17.0) + kBallR * n);
    a.push_back((n + std::tan(10.0 * kDeg) * block.tangent(u)).normalized());
  }
  cl.pass(c, a);
  cl.end();
}

void rotary_floor(JobCl& cl) {
  const double slope = std::atan2(kConeDrop, kConeR1 - kConeR0);  // the normal's polar angle
  cl.operation("ROTARY_FLOOR");
  for (double r : {56.0, 64.0}) {
    const double z = -kConeDrop * (r - kConeR0) / (kConeR1 - kConeR0);
    std::vector<Vec3d> c, a;
    for (int k = 0; k <= 180; ++k) {
      const double phi = 2.0 * kDeg * k;
      c.push_back(Vec3d(r * std::cos(phi), r * std::sin(phi), z) + kBallR * leaning(slope, phi));
      a.push_back(leaning(slope + 5.0 * kDeg, phi));  // 5 deg off the normal, outward
    }
    cl.pass(c, a);
  }
  cl.end();
}

void fillet(JobCl& cl) {
  cl.operation("FILLET");
  for (double beta_deg : {55.0, 65.0}) {
    const double beta = beta_deg * kDeg;
    const double r = kFilletCentreR - (kFilletR - kBallR) * std::sin(beta);
    const double z = kFilletCentreZ - (kFilletR - kBallR) * std::cos(beta);
    std::vector<Vec3d> c, a;
    for (int k = 0; k <= 120; ++k) {
      const double phi = 1.5 * kDeg * k;
      c.push_back(Vec3d(r * std::cos(phi), r * std::sin(phi), z));
      // Near upright, leaning 0.5 to 3.5 deg off the boss as an interpolated axis wavers.
      a.push_back(leaning((2.0 + 1.5 * std::sin(6.0 * phi)) * kDeg, phi));
    }
    cl.pass(c, a);
  }
  cl.end();
}

/// Round the oval boss's undercut fillet, the tool leaning out over the floor 12 to 16 deg (the
/// wall overhangs at 12: a tool leaning less reaches into it), C turning fast round the ends.
void curve_fillet(JobCl& cl) {
  cl.operation("CURVE_FILLET");
  const Loop oval = oval_loop();
  const Eigen::Vector2d f = undercut_fillet_centre();
  const double beta = 80.0 * kDeg;
  const double d = f.x() - (kFilletR - kBallR) * std::sin(beta);
  const double z = f.y() - (kFilletR - kBallR) * std::cos(beta);
  std::vector<Vec3d> c, a;
  for (int k = 0; k <= 180; ++k) {
    const double t = 2.0 * kDeg * k;
    const double lean = (14.0 + 2.0 * std::sin(5.0 * t)) * kDeg;
    c.push_back(oval.at(t / (2.0 * M_PI), d, z));
    a.push_back(std::cos(lean) * Vec3d::UnitZ() + std::sin(lean) * oval.normal(t / (2.0 * M_PI)));
  }
  cl.pass(c, a);
  cl.end();
}

/// A loop on the floor (z = 0) about `centre` with half-axes ax, ay, `turn` +1 anticlockwise,
/// the axis 15 deg off the normal toward the direction of travel (`side`: to its right).
void floor_loop(JobCl& cl, const std::string& name, const Vec3d& centre, double ax, double ay,
                int turn, bool side) {
  cl.operation(name);
  std::vector<Vec3d> c, a;
  for (int k = 0; k <= 180; ++k) {
    const double t = turn * 2.0 * kDeg * k;
    c.push_back(centre + Vec3d(ax * std::cos(t), ay * std::sin(t), kBallR));
    const Vec3d dir = Vec3d(-ax * std::sin(t), ay * std::cos(t), 0.0).normalized() * turn;
    const Vec3d off = side ? Vec3d(dir.cross(Vec3d::UnitZ())) : dir;
    a.push_back(std::cos(15.0 * kDeg) * Vec3d::UnitZ() + std::sin(15.0 * kDeg) * off);
  }
  cl.pass(c, a);
  cl.end();
}

}  // namespace

/// The boss (radius 14, 20 high) with its fillet, the floor out to the cone, the cone, the sides;
/// the bar (x -150 to -125) whose top edge facing -x is a 6 mm chamfer at 45 deg; the oval boss;
/// a block of rounded corners (x 120 to 160) with the same chamfer round its top.
TriangleMesh real_job_part() {
  std::vector<Eigen::Vector2d> rz{{0.0, 20.0}, {14.0, 20.0}};
  for (int k = 16; k >= 0; --k) {
    const double beta = 0.5 * M_PI * k / 16;
    rz.emplace_back(kFilletCentreR - kFilletR * std::sin(beta),
                    kFilletCentreZ - kFilletR * std::cos(beta));
  }
  for (const auto& q : std::vector<Eigen::Vector2d>{
           {kConeR0, 0.0}, {kConeR1, -kConeDrop}, {kConeR1, -30.0}, {0.0, -30.0}}) {
    rz.push_back(q);
  }
  TriangleMesh part;
  append(part, revolved_profile(rz, 240));
  append(part,
         extruded_profile(
             {{-150.0, 14.0}, {-144.0, 20.0}, {-125.0, 20.0}, {-125.0, -30.0}, {-150.0, -30.0}},
             -40.0, 40.0, 8));
  append(part, oval_boss());
  append(part, swept(block_loop(), {{-6.0, 20.0}, {0.0, 14.0}, {0.0, -30.0}}, 480));
  return part;
}

std::string real_job_cl() {
  JobCl cl;
  chamfer(cl);
  outline_chamfer(cl);
  rotary_floor(cl);
  fillet(cl);
  curve_fillet(cl);
  floor_loop(cl, "OVAL", Vec3d(35.0, 0.0, 0.0), 8.0, 4.0, 1, false);
  floor_loop(cl, "OVAL_OPPOSITE", Vec3d(0.0, 35.0, 0.0), 4.0, 8.0, -1, true);
  floor_loop(cl, "CIRCLE", Vec3d(-35.0, 0.0, 0.0), 6.0, 6.0, 1, false);
  cl.os << "FINI\n";
  return cl.os.str();
}

}  // namespace taxopt::test
