// Head machines (docs/kinematics.md "Head machines"): a head-table machine (the head tilts the
// tool, the table turns the workpiece about C: LinuxCNC's maxkins) and a head-head machine (the
// head turns the tool about C and tilts it: LinuxCNC's 5axiskins bridge mill). Each has the
// property tests the table-table ones have -- forward after inverse on both branches, the pole,
// the joints' round trip, the limits -- and its joints are those LinuxCNC's kinematics module
// computes, written out here from the modules' formulas (maxkins.c, 5axiskins.c), not from the
// library. The demo posts and verifies on both sample machines, and rs274 runs the bridge
// mill's program with its own configuration.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"
#include "taxopt/kinematics/machine.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

Machine shipped(const std::string& name) {
  return read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/" + name + ".toml");
}

/// The joints LinuxCNC's modules give for a tip (workpiece, mm) at machine B and C (deg), with
/// L their pivot length plus the tool length, maxkins in its default (unconventional) B.
Vec3d maxkins_joints(const Vec3d& tip, double b_deg, double c_deg, double l) {
  const double b = deg_to_rad(b_deg), c = deg_to_rad(c_deg);
  // max_inverse: the tip turned by -C about the table's origin, then the head's swing.
  const double r = std::hypot(tip.x(), tip.y());
  const double theta = std::atan2(tip.y(), tip.x()) - c;
  return {r * std::cos(theta) - l * std::sin(b), r * std::sin(theta),
          tip.z() + l * std::cos(b) - l};
}
Vec3d fiveaxiskins_joints(const Vec3d& tip, double b_deg, double c_deg, double l) {
  const double b = deg_to_rad(b_deg), c = deg_to_rad(c_deg);
  // kinematicsInverse: joints = tip - s2r(L, C, 180 - B) - (0, 0, L).
  const double p = deg_to_rad(180.0) - b;
  return tip -
         Vec3d(l * std::sin(p) * std::cos(c), l * std::sin(p) * std::sin(c), l * std::cos(p) + l);
}

}  // namespace

TEST_CASE(
    "head machines: the joints of a head-table and a head-head machine are LinuxCNC's maxkins' "
    "and 5axiskins', and come back to the tip",
    "[kinematics][head]") {
  std::mt19937 rng(46);
  std::uniform_real_distribution<double> u(-80.0, 80.0), ub(-89.0, 89.0), uc(-400.0, 400.0);
  for (const char* name : {"linuxcnc-max5", "linuxcnc-5axis-bridgemill"}) {
    INFO(name);
    Machine m = shipped(name);
    const bool head_head = m.rotary.layout == RotaryLayout::HeadHead;
    CHECK(m.rotary.layout == (head_head ? RotaryLayout::HeadHead : RotaryLayout::HeadTable));
    CHECK(m.rotary.tilt_letter() == 'B');
    for (const double l : {0.0, 250.0, 317.5}) {
      m.rotary.head_length_mm = l;
      for (int trial = 0; trial < 200; ++trial) {
        const Vec3d tip(u(rng), u(rng), u(rng));
        const double b = ub(rng), c = uc(rng);
        const Posed pose{deg_to_rad(b), deg_to_rad(c)};
        const Vec3d joints = m.rotary.to_machine_mm(tip, pose);
        const Vec3d want =
            head_head ? fiveaxiskins_joints(tip, b, c, l) : maxkins_joints(tip, b, c, l);
        INFO("L " << l << " B " << b << " C " << c);
        CHECK((joints - want).norm() < 1e-9);
        CHECK((m.rotary.from_machine_mm(joints, pose) - tip).norm() < 1e-9);
        // The tool axis the modules' swing implies: (tip - joints) / L + z (at L > 0).
        if (l > 0.0) {
          const Vec3d swing = head_head ? joints - tip
                                        : Eigen::AngleAxisd(deg_to_rad(c), Vec3d::UnitZ()) *
                                              (joints - maxkins_joints(tip, 0.0, c, l));
          CHECK((swing / l + Vec3d::UnitZ() - m.rotary.forward(pose)).norm() < 1e-9);
        }
      }
      // At B = 0 the joints are the tip (head-head) or the tip turned with the table.
      const Vec3d tip(12.0, -7.0, 3.0);
      const Posed flat{0.0, deg_to_rad(30.0)};
      CHECK((m.rotary.to_machine_mm(tip, flat) -
             (head_head ? tip : Eigen::AngleAxisd(deg_to_rad(-30.0), Vec3d::UnitZ()) * tip))
                .norm() < 1e-12);
    }
  }
}

TEST_CASE(
    "head machines: inverse undoes forward on both branches, the pole frees C, and a B range "
    "limits which axes are reachable",
    "[kinematics][head]") {
  std::mt19937 rng(4646);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const char* name : {"linuxcnc-max5", "linuxcnc-5axis-bridgemill"}) {
    INFO(name);
    const Machine m = shipped(name);
    for (int trial = 0; trial < 500; ++trial) {
      const Vec3d axis = Vec3d(n(rng), n(rng), n(rng)).normalized();
      const auto branches = m.rotary.inverse(axis);
      for (const Posed& p : branches) CHECK((m.rotary.forward(p) - axis).norm() < 1e-9);
      // Both branches tilt by the same angle, on either side.
      CHECK(std::abs(branches[0].tilt_rad + branches[1].tilt_rad) < 1e-12);
      // B within +-90 (max5) reaches the upper hemisphere only; +-120 (bridge mill) beyond.
      const double tilt_deg = rad_to_deg(std::acos(std::clamp(axis.z(), -1.0, 1.0)));
      const double b_max = rad_to_deg(m.rotary.tilt.max_rad);
      CHECK(m.rotary.reachable(axis) == (tilt_deg <= b_max + 1e-6));
    }
    CHECK(m.rotary.at_pole(Vec3d::UnitZ()));
    const auto pole = m.rotary.inverse(Vec3d::UnitZ());
    CHECK(pole[0].tilt_rad == 0.0);
  }
}

TEST_CASE(
    "head machines: a machine file names its layout, its pivot length in range, and machine "
    "mode is refused naming why",
    "[kinematics][head][io]") {
  const Machine bridge = shipped("linuxcnc-5axis-bridgemill");
  CHECK(bridge.kinematics == "bc-head-head");
  CHECK(bridge.head_pivot_length_mm == 250.0);
  CHECK_NOTHROW(validate(bridge));
  const std::string text =
      read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/linuxcnc-5axis-bridgemill.toml");
  const auto edited = [&](const std::string& from, const std::string& to) {
    return replaced_once(text, from, to);
  };
  const auto error_of = [](const std::string& toml) {
    return input_error_of([&] { (void)parse_machine_toml(toml, "m.toml"); });
  };
  CHECK_THAT(error_of(edited("mode = \"tcp\"", "mode = \"machine\"")),
             Catch::Contains("gcode.mode \"machine\" on a bc-head-head machine is not written"));
  CHECK_THAT(error_of(edited("head_pivot_length = 250.0", "head_pivot_length = -1.0")),
             Catch::Contains("pivot.head_pivot_length must be within [0, 5000] mm"));
  CHECK_THAT(error_of(edited("head_pivot_length = 250.0", "b_axis_x = 1.0")),
             Catch::Contains("b_axis_x"));
  // No pivot length: never assumed 0 (issue 63.12).
  CHECK_THAT(error_of(edited("head_pivot_length = 250.0", "c_axis_x = 0.0")),
             Catch::Contains("a head machine needs [pivot] head_pivot_length"));
  CHECK_THAT(error_of(edited("\"bc-head-head\"", "\"bc-head-tail\"")),
             Catch::Contains("ac-head-head, bc-head-head"));
  // In code: the name must say the layout it holds, and a head has no machine mode.
  Machine wrong = bridge;
  wrong.kinematics = "bc-table-table";
  CHECK_THAT(input_error_of([&] { validate(wrong); }), Catch::Contains("\"bc-head-head\""));
  Machine machine_mode = bridge;
  machine_mode.gcode.mode = GcodeMode::Machine;
  CHECK_THAT(input_error_of([&] { validate(machine_mode); }), Catch::Contains("is not written"));
}

TEST_CASE(
    "head machines: the demo posts and verifies on LinuxCNC's head-table and head-head samples, "
    "and rs274 runs each program with the sample's own configuration",
    "[kinematics][head][rs274][integration]") {
  REQUIRE(have_rs274());
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/";
  for (const char* name : {"linuxcnc-max5", "linuxcnc-5axis-bridgemill"}) {
    INFO(name);
    TempDir t;
    // The sample machines' travel is the simulated machine's, not the demo part's (the max5's
    // Z ends at +1 mm): left out, as the work offset would place the part.
    std::string toml;
    {
      std::istringstream in(read_file(d + "machines/" + name + ".toml"));
      for (std::string line; std::getline(in, line);) {
        if (line.rfind("min_mm", 0) == 0 || line.rfind("max_mm", 0) == 0) continue;
        if (line.rfind("retract_z_mm", 0) == 0) line = "retract_z_mm = 100.0";
        toml += line + "\n";
      }
    }
    write_file(t.path("m.toml"), toml);
    const RunResult r =
        run_taxopt("--in " + d + "demo/sine.cls --part " + d + "demo/sine.stl --machine " +
                   t.path("m.toml") + " --method global --feed-schedule --gauge-length 60 -q" +
                   " --gcode " + t.path("o.ngc") + " --report " + t.path("r.json"));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto report = nlohmann::json::parse(read_file(t.path("r.json")));
    CHECK(report["ok"] == true);
    CHECK(report["kinematics"] ==
          (std::string(name) == "linuxcnc-max5" ? "bc-head-table" : "bc-head-head"));
    for (const auto& op : report["operations"]) {
      CHECK(op["after"]["colliding_points"] == 0);
      CHECK(op["verification"]["collision_free"] == true);
    }
    const std::string text = read_file(t.path("o.ngc"));
    CHECK(text.find(" B") != std::string::npos);
    CHECK(text.find(" A") == std::string::npos);
    // rs274 with the sample's own configuration (the bridge mill's remapped M428/M429 stubbed:
    // they read a HAL pin rs274 alone does not have): every point's tip and axis as taxopt
    // meant them.
    const bool bridge = std::string(name) == "linuxcnc-5axis-bridgemill";
    Rs274Options sample;
    sample.ini = std::string("/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/") +
                 (bridge ? "5axis/bridgemill/5axis.ini" : "5axis/max5/max5kins.ini");
    sample.stub_switchkins = bridge;
    std::vector<CanonMove> points, all;
    const RunResult rs = run_rs274(t.path("o.ngc"), points, sample, &all);
    INFO(rs.err);
    REQUIRE(rs.code == 0);
    // The program's last point is the CL file's last, tilted as the report's last row says.
    std::size_t n = 0;
    for (const auto& op : report["operations"]) n += op["points"].get<std::size_t>();
    INFO("rs274 moves " << points.size() << " of " << all.size() << ", CL points " << n);
    REQUIRE(points.size() == n);
    // TCP: the words are the tip in the workpiece. The method keeps each ball centre and turns
    // the axis about it, so the centre rs274's words give -- the tip plus the ball radius along
    // the axis the module's own formula makes of the B and C it read (5axiskins: (-sin B cos C,
    // -sin B sin C, cos B); maxkins: Rot(Z, C) (-sin B, 0, cos B), the same) -- is the CL file's,
    // to the written decimals, and that axis within the run's cone of the CL file's. Each CL point
    // against the move whose centre is nearest.
    const Toolpath tp = read_cl_file(d + "demo/sine.cls");
    double worst_tip = 0.0, worst_axis_deg = 0.0;
    const auto axis_of = [](const CanonMove& mv) {
      const double b = deg_to_rad(mv.b), c = deg_to_rad(mv.c);
      return Vec3d(-std::sin(b) * std::cos(c), -std::sin(b) * std::sin(c), std::cos(b));
    };
    for (const auto& op : tp.operations) {
      const double radius = op.tool.ball_radius_mm();
      REQUIRE(radius > 0.0);
      for (const auto& p : op.points) {
        const Vec3d centre = p.tip_mm + radius * p.axis;
        const CanonMove* at = nullptr;
        double best = 1e300;
        for (const CanonMove& mv : all) {
          const double dist = (Vec3d(mv.x, mv.y, mv.z) + radius * axis_of(mv) - centre).norm();
          if (dist < best) best = dist, at = &mv;
        }
        REQUIRE(at);
        worst_tip = std::max(worst_tip, best);
        worst_axis_deg = std::max(worst_axis_deg, rad_to_deg(angle_between(axis_of(*at), p.axis)));
      }
    }
    CHECK(worst_tip < 1e-3);
    CHECK(worst_axis_deg <= report["options"]["max_deviation_deg"].get<double>() + 1e-3);
  }
}

namespace {

/// The imported machine's axes, limits and pivot equal the shipped machine file's.
void check_same_machine(const Machine& imported, const Machine& shipped) {
  CHECK(imported.kinematics == shipped.kinematics);
  CHECK(imported.rotary.layout == shipped.rotary.layout);
  CHECK(imported.rotary.tilt_about == shipped.rotary.tilt_about);
  CHECK(imported.rotary.tilt.sense == shipped.rotary.tilt.sense);
  CHECK(imported.rotary.c.sense == shipped.rotary.c.sense);
  CHECK(imported.rotary.tilt.min_rad == Approx(shipped.rotary.tilt.min_rad));
  CHECK(imported.rotary.tilt.max_rad == Approx(shipped.rotary.tilt.max_rad));
  CHECK(imported.rotary.c.min_rad == Approx(shipped.rotary.c.min_rad));
  CHECK(imported.rotary.c.max_rad == Approx(shipped.rotary.c.max_rad));
  CHECK(imported.head_pivot_length_mm == shipped.head_pivot_length_mm);
  for (std::size_t j = 0; j < kJointCount; ++j) {
    INFO("joint " << j);
    CHECK(imported.limits[j].max_velocity_per_s == shipped.limits[j].max_velocity_per_s);
    CHECK(imported.limits[j].max_accel_per_s2 == shipped.limits[j].max_accel_per_s2);
  }
  for (std::size_t q = 0; q < 3; ++q) {
    CHECK(imported.linear_range[q].min_mm == shipped.linear_range[q].min_mm);
    CHECK(imported.linear_range[q].max_mm == shipped.linear_range[q].max_mm);
  }
}

}  // namespace

TEST_CASE(
    "machine: LinuxCNC's max5 (maxkins) sample imports as the shipped head-table machine and "
    "its bridge mill (5axiskins) as the head-head one once its pivot length is a number",
    "[cli][machine][head]") {
  const std::string samples =
      "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/";
  const std::string machines = std::string(TAXOPT_SOURCE_DIR) + "/data/machines/";
  TempDir t;
  // max5kins.ini #INCLUDEs max5_base.inc (its axes, LINEAR_UNITS = 1.0: units per mm) and its
  // HAL sets maxkins.pivot-length to [MAX]B_PIVOT_LENGTH (0).
  const RunResult max5 = run_taxopt("machine --from-linuxcnc-ini " + samples +
                                    "max5/max5kins.ini --out " + t.path("max5.toml"));
  INFO(max5.err);
  REQUIRE(max5.code == 0);
  check_same_machine(read_machine_file(t.path("max5.toml")),
                     read_machine_file(machines + "linuxcnc-max5.toml"));
  // B is joint 4 in maxkins (X Y Z A B C), not the 4th letter of COORDINATES = X Y Z B C.
  CHECK_THAT(read_file(t.path("max5.toml")), Catch::Contains("maxkins"));

  // The bridge mill's pivot length comes from its GUI (5axisgui.pivot_len, summed with the
  // tool offset in HAL): not a number its files hold, so refused naming the pin and the line.
  const std::string bridge = samples + "bridgemill/";
  const RunResult refused = run_taxopt("machine --from-linuxcnc-ini " + bridge + "5axis.ini");
  CHECK(refused.code == 2);
  CHECK_THAT(refused.err, Catch::Contains("5axis.ini:98") &&
                              Catch::Contains("5axiskins.pivot-length is not set"));
  // The same configuration with a shop's HAL in place of the GUI's, setting the pin: the
  // shipped machine.
  write_file(t.path("5axis_postgui.hal"), read_file(bridge + "5axis_postgui.hal"));
  write_file(t.path("shop.hal"), "setp 5axiskins.pivot-length 250\n");
  const std::string ini = replaced_once(read_file(bridge + "5axis.ini"), "HALFILE = 5axisgui.hal\n",
                                        "HALFILE = shop.hal\n");
  write_file(t.path("bridge.ini"), ini);
  const RunResult set = run_taxopt("machine --from-linuxcnc-ini " + t.path("bridge.ini") +
                                   " --out " + t.path("bridge.toml"));
  INFO(set.err);
  REQUIRE(set.code == 0);
  check_same_machine(read_machine_file(t.path("bridge.toml")),
                     read_machine_file(machines + "linuxcnc-5axis-bridgemill.toml"));
}

TEST_CASE(
    "head machines: make_machine builds each kinematics from its one name, a head with its "
    "pivot, and no machine is taken with a head and no pivot or a table and one",
    "[kinematics][head][library]") {
  const struct {
    const char* name;
    TiltAxis tilt;
    RotaryLayout layout;
  } kinds[] = {{"ac-table-table", TiltAxis::X, RotaryLayout::TableTable},
               {"bc-table-table", TiltAxis::Y, RotaryLayout::TableTable},
               {"ac-head-table", TiltAxis::X, RotaryLayout::HeadTable},
               {"bc-head-table", TiltAxis::Y, RotaryLayout::HeadTable},
               {"ac-head-head", TiltAxis::X, RotaryLayout::HeadHead},
               {"bc-head-head", TiltAxis::Y, RotaryLayout::HeadHead}};
  for (const auto& k : kinds) {
    INFO(k.name);
    const bool head = k.layout != RotaryLayout::TableTable;
    const Machine m = head ? make_machine(k.name, 250.0) : make_machine(k.name);
    CHECK(m.kinematics == k.name);
    CHECK(m.rotary.tilt_about == k.tilt);
    CHECK(m.rotary.layout == k.layout);
    CHECK(m.rotary.tilt_letter() == (k.tilt == TiltAxis::X ? 'A' : 'B'));
    CHECK_NOTHROW(validate(m));
    if (head) {
      CHECK(m.head_pivot_length_mm == 250.0);
      CHECK_THAT(input_error_of([&] { (void)make_machine(k.name); }),
                 Catch::Contains("Machine::head_pivot_length_mm: a " + std::string(k.name) +
                                 " machine needs its head's pivot length"));
      CHECK_NOTHROW(make_machine(k.name, 0.0));  // LinuxCNC's max5: stated, so taken
    } else {
      CHECK_THAT(input_error_of([&] { (void)make_machine(k.name, 250.0); }),
                 Catch::Contains("Machine::head_pivot_length_mm must be empty"));
    }
  }
  CHECK_THAT(input_error_of([&] { (void)make_machine("bc-trunnion"); }),
             Catch::Contains("'bc-trunnion' is no kinematics"));
  // A head machine made by hand without its pivot: refused by validate, as by run_job.
  Machine by_hand = default_machine();
  by_hand.kinematics = "ac-head-head";
  by_hand.rotary.layout = RotaryLayout::HeadHead;
  CHECK_THAT(input_error_of([&] { validate(by_hand); }),
             Catch::Contains("needs its head's pivot length"));
}
