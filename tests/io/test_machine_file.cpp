#include <catch2/catch.hpp>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/machine_file.hpp"

using namespace taxopt;

namespace {

const char* kFull = R"(name = "generic-ac-trt"
kinematics = "ac-table-table"

[axes.A]
min_deg = -120.0
max_deg = 120.0
sense = 1
max_velocity_deg_s = 3600.0
max_accel_deg_s2 = 36000.0

[axes.C]
continuous = true
sense = -1
max_velocity_deg_s = 7200.0
max_accel_deg_s2 = 72000.0

[pivot]
a_axis_y = 1.5
a_axis_z = -2.0
c_axis_x = 3.0
c_axis_y = 4.0

[gcode]
dialect = "linuxcnc"
mode = "machine"
feed_mode = "inverse-time"
feed_reference = "tip"
decimals = 5
)";

void expect_error(const std::string& text, int line, const std::string& says) {
  try {
    parse_machine_toml(text, "m.toml");
    FAIL("accepted: " << says);
  } catch (const InputError& e) {
    CHECK(e.file() == "m.toml");
    CHECK(e.line() == line);
    CHECK_THAT(e.message(), Catch::Contains(says));
  }
}

std::string replace(const std::string& s, const std::string& from, const std::string& to) {
  return taxopt::test::replaced_once(s, from, to);
}

}  // namespace

TEST_CASE("machine file: the example of CLI.md reads completely", "[io][machine]") {
  const Machine m = parse_machine_toml(kFull, "m.toml");
  CHECK(m.name == "generic-ac-trt");
  CHECK(rad_to_deg(m.rotary.tilt.min_rad) == Approx(-120.0));
  CHECK(m.limits[3].max_accel_per_s2 == 36000.0);
  CHECK(m.limits[4].max_velocity_per_s == 7200.0);
  CHECK(m.limits[0].max_velocity_per_s == 0.0);  // not given
  CHECK(m.rotary.c.continuous);
  CHECK(m.rotary.c.sense == -1);
  CHECK(m.rotary.tilt_axis_point_mm == Vec3d(0, 1.5, -2.0));
  CHECK(m.rotary.c_axis_point_mm == Vec3d(3.0, 4.0, 0));
  CHECK(m.gcode.mode == GcodeMode::Machine);
  CHECK(m.gcode.feed_mode == FeedMode::InverseTime);
  CHECK(m.gcode.feed_reference == FeedReference::Tip);
  CHECK(m.gcode.decimals == 5);
  CHECK(default_machine().gcode.feed_reference == FeedReference::CutterPath);
}

TEST_CASE("machine file: the example docs/cli.md shows users reads as it is, every key in it",
          "[io][machine]") {
  const std::string doc = taxopt::test::read_file(std::string(TAXOPT_SOURCE_DIR) + "/docs/cli.md");
  const std::size_t section = doc.find("## Machine file (TOML)");
  REQUIRE(section != std::string::npos);
  const std::size_t begin = doc.find("```toml\n", section);
  REQUIRE(begin != std::string::npos);
  const std::size_t end = doc.find("```", begin + 8);
  REQUIRE(end != std::string::npos);
  const std::string example = doc.substr(begin + 8, end - begin - 8);
  INFO(example);
  const Machine m = parse_machine_toml(example, "docs/cli.md");
  CHECK(m.limits[0].max_accel_per_s2 == 3000.0);
  CHECK(m.joint_max_accel_per_s2[0] == 3000.0);
  CHECK(m.gcode.program.tcp_on == std::vector<std::string>{"M428"});
}

TEST_CASE("machine file: X Y Z limits and jerk, and the defaults where none is given",
          "[io][machine][feed]") {
  const Machine m =
      parse_machine_toml(replace(kFull, "[pivot]",
                                 "[axes.X]\nmax_velocity_mm_s = 400.0\nmax_accel_mm_s2 = 2500\n"
                                 "[axes.Z]\nmax_jerk_mm_s3 = 50000.0\n\n[pivot]"),
                         "m.toml");
  CHECK(m.limits[0].max_velocity_per_s == 400.0);
  CHECK(m.limits[0].max_accel_per_s2 == 2500.0);
  CHECK(m.limits[2].max_jerk_per_s3 == 50000.0);
  const JointLimits e = effective_limits(m);
  CHECK(e[0].max_velocity_per_s == 400.0);                                         // given
  CHECK(e[1].max_velocity_per_s == default_joint_limits()[1].max_velocity_per_s);  // default
  CHECK(e[3].max_accel_per_s2 == 36000.0);
  for (const JointLimit& l : default_joint_limits()) {
    CHECK(l.max_velocity_per_s > 0.0);
    CHECK(l.max_accel_per_s2 > 0.0);
  }
  expect_error(replace(kFull, "[pivot]", "[axes.X]\nmax_velocity_deg_s = 4.0\n[pivot]"), 18,
               "unknown key 'axes.X.max_velocity_deg_s'");
  expect_error(replace(kFull, "[pivot]", "[axes.Y]\nmax_accel_mm_s2 = 0\n[pivot]"), 18,
               "axes.Y.max_accel_mm_s2 must be positive");
  expect_error(replace(kFull, "[pivot]", "[axes.Q]\n[pivot]"), 17, "unknown key 'axes.Q'");
  // The joints' own accelerations (LinuxCNC's [JOINT_n] with TCP on): where not given, the
  // axis's; given, in the axis's unit.
  const Machine j = parse_machine_toml(
      replace(replace(kFull, "[pivot]", "[axes.Y]\njoint_max_accel_mm_s2 = 320\n[pivot]"),
              "max_accel_deg_s2 = 36000.0",
              "max_accel_deg_s2 = 36000.0\njoint_max_accel_deg_s2 = 4e4"),
      "m.toml");
  CHECK(joint_accel_limit(j, effective_limits(j), 1) == 320.0);
  CHECK(joint_accel_limit(j, effective_limits(j), 3) == 40000.0);
  CHECK(joint_accel_limit(j, effective_limits(j), 0) == effective_limits(j)[0].max_accel_per_s2);
  CHECK(joint_accel_limit(m, e, 3) == 36000.0);
  for (const char* bad : {"0", "-300", "nan", "inf", "\"fast\""}) {
    INFO(bad);
    expect_error(replace(kFull, "[pivot]",
                         std::string("[axes.Y]\njoint_max_accel_mm_s2 = ") + bad + "\n[pivot]"),
                 18, "axes.Y.joint_max_accel_mm_s2 must be");
  }
  expect_error(replace(kFull, "[pivot]", "[axes.Y]\njoint_max_accel_deg_s2 = 300\n[pivot]"), 18,
               "unknown key 'axes.Y.joint_max_accel_deg_s2'");
}

TEST_CASE("machine file: every shipped machine file reads", "[io][machine]") {
  for (const char* f : {"generic-ac-trt.toml", "linuxcnc-xyzac-trt.toml", "paper-ac.toml"}) {
    INFO(f);
    CHECK_NOTHROW(read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/" + f));
  }
}

TEST_CASE("machine file: errors name the line and what was expected", "[io][machine][bad-input]") {
  expect_error(replace(kFull, "sense = 1\n", "sense = 1\nspeed = 3\n"), 8,
               "unknown key 'axes.A.speed'");
  expect_error(replace(kFull, "max_deg = 120.0", "max_deg = -130.0"), 5,
               "min_deg must be less than max_deg");
  expect_error(replace(kFull, "sense = -1", "sense = 2"), 13, "sense must be 1 or -1");
  expect_error(replace(kFull, "decimals = 5", "decimals = 9"), 28, "decimals");
  expect_error(replace(kFull, "\"tip\"", "\"nose\""), 27,
               "gcode.feed_reference must be \"cutter-path\" or \"tip\", got 'nose'");
  expect_error(
      replace(kFull, "\"linuxcnc\"", "\"mazatrol\""), 24,
      "gcode.dialect must be \"linuxcnc\", \"fanuc\", \"siemens\", \"heidenhain\" or \"haas\"");
  // Heidenhain's ISO mode has no G93: refused where the file asks for both.
  expect_error(replace(kFull, "\"linuxcnc\"", "\"heidenhain\""), 26, "no G93");
  for (const char* d : {"linuxcnc", "fanuc", "siemens"}) {
    const Machine m = parse_machine_toml(
        replace(replace(kFull, "linuxcnc", d), "decimals = 5", "decimals = 4"), "m.toml");
    CHECK(std::string(to_string(m.gcode.dialect)) == d);
  }
  // A controller's number format: Fanuc takes 4 decimals at most (IS-C), a TNC 4 and F 3.
  expect_error(replace(kFull, "\"linuxcnc\"", "\"fanuc\""), 28, "0 to 4 (the most fanuc takes)");
  expect_error(replace(replace(replace(kFull, "\"linuxcnc\"", "\"heidenhain\""), "\"inverse-time\"",
                               "\"units-per-minute\""),
                       "decimals = 5", "decimals = 4\nfeed_decimals = 4"),
               29, "0 to 3 (the most heidenhain takes)");
  expect_error(replace(kFull, "mode = \"machine\"", "mode = \"head\""), 25, "tcp");
  expect_error(replace(kFull, "min_deg = -120.0", "min_deg = \"low\""), 5, "must be a number");
  expect_error(replace(kFull, "[axes.C]\ncontinuous = true\n", "[axes.C]\n"), 11,
               "needs min_deg and max_deg");
  expect_error(replace(kFull, "kinematics = \"ac-table-table\"", "kinematics = \"bc-head\""), 2,
               "not supported");
  expect_error(replace(kFull, "kinematics = \"ac-table-table\"\n", ""), 0,
               "missing key 'kinematics'");
  expect_error("kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -1\nmax_deg = 1\n", 0,
               "missing section [axes.C]");
  expect_error("kinematics = = 3\n", 1, "not valid TOML");
  expect_error(replace(kFull, "max_accel_deg_s2 = 36000.0", "max_accel_deg_s2 = -1.0"), 9,
               "must be positive");
  // Found by fuzz_machine_file: an integer no double holds exactly threw bad_optional_access.
  expect_error(replace(kFull, "min_deg = -120.0", "min_deg = -9007199254740995"), 5,
               "within [-360, 360]");
  expect_error(
      replace(kFull, "max_velocity_deg_s = 3600.0", "max_velocity_deg_s = -9007199254740993"), 8,
      "must be positive");
  // Found by fuzz_machine_file: a float where an integer belongs, too large for one
  // (toml++ converted it with undefined behaviour before the type was tested).
  expect_error(replace(kFull, "sense = -1", "sense = 6.0e58"), 13, "sense must be 1 or -1");
  expect_error(replace(kFull, "sense = -1", "sense = 1.0"), 13, "sense must be 1 or -1");
  expect_error(replace(kFull, "decimals = 5", "decimals = 1e300"), 28, "decimals");
}

TEST_CASE("machine file: clearances, the usual holder and the linear travel", "[io][machine]") {
  const std::string head =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n";
  const Machine m = parse_machine_toml(
      head +
          "[axes.Z]\nmin_mm = -300\nmax_mm = 50\n[checks]\nshank_clearance_mm = 0.3\n"
          "holder_clearance_mm = 2\n[holder]\nradius_mm = 16\nlength_mm = 60\n"
          "gauge_length_mm = 45\n",
      "m.toml");
  CHECK(m.shank_clearance_mm == Approx(0.3));
  CHECK(m.holder_clearance_mm == Approx(2.0));
  CHECK(m.holder_radius_mm == Approx(16.0));
  CHECK(m.holder_length_mm == Approx(60.0));
  CHECK(m.holder_gauge_length_mm == Approx(45.0));
  CHECK(m.linear_range[2].min_mm == -300.0);
  CHECK(m.linear_range[2].max_mm == 50.0);
  CHECK_FALSE(m.linear_range[0].bounded());
  const auto refused = [&](const std::string& text, const std::string& says) {
    try {
      parse_machine_toml(head + text, "m.toml");
    } catch (const InputError& e) {
      INFO(e.what());
      return std::string(e.what()).find(says) != std::string::npos;
    }
    return false;
  };
  CHECK(refused("[checks]\nshank_clearance_mm = -1\n", "checks.shank_clearance_mm must be >= 0"));
  CHECK(refused("[holder]\nlength_mm = 60\n", "[holder] needs radius_mm"));
  CHECK(refused("[holder]\nradius_mm = 0\n", "holder.radius_mm must be positive"));
  CHECK(refused("[axes.X]\nmin_mm = 5\nmax_mm = -5\n", "min_mm must be less than max_mm"));
  CHECK(refused("[checks]\nclearance = 1\n", "clearance"));
}

TEST_CASE("machine file: the program template and the safe retract", "[io][machine]") {
  const std::string head =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n[gcode]\ndialect = \"fanuc\"\n";
  const Machine m = parse_machine_toml(
      head +
          "program_name = \"PART_7\"\nprogram_number = 7\nwork_offset = \"G54.1 P3\"\n"
          "coolant = \"mist\"\nheader = [\"G5.1 Q1 (AICC on)\"]\nfooter = [\"M1\"]\n"
          "tool_change = [\"T{tool} M6\"]\nsafe_retract = \"none\"\nretract_z_mm = -5\n"
          "linearise_tolerance_mm = 0.002\nfeed_decimals = 2\n",
      "m.toml");
  const ProgramTemplate& t = m.gcode.program;
  CHECK(t.name == "PART_7");
  CHECK(t.number == 7);
  CHECK(t.work_offset == "G54.1 P3");
  CHECK(t.coolant == Coolant::Mist);
  CHECK(t.header == std::vector<std::string>{"G5.1 Q1 (AICC on)"});
  CHECK(t.footer == std::vector<std::string>{"M1"});
  CHECK(t.tool_change == std::vector<std::string>{"T{tool} M6"});
  CHECK(t.retract == SafeRetract::None);
  CHECK(t.retract_z_mm == -5.0);
  CHECK(t.linearise_tolerance_mm == 0.002);
  CHECK(m.gcode.feed_decimals == 2);
  // A template block may not move the machine nor change a mode taxopt writes itself.
  expect_error(head + "header = [\"M1 X0\"]\n", 9, "moves an axis (X)");
  expect_error(head + "header = [\"G0 X0\"]\n", 9, "holds G0");
  expect_error(head + "footer = [\"G91 G28 Z0\"]\n", 9, "home the rotary axes only");
  expect_error(head + "header = [\"G91 G28 C0\"]\n", 9, "holds G91");
  expect_error(head + "tool_change = [\"M6\"]\n", 9, "must call the tool by \"{tool}\"");
  expect_error(head + "tcp_on = [\"G49\"]\n", 9, "holds G49");
  // Blocks that move or reframe the machine, found through rs274, each refused.
  for (const auto& [block, says] : std::vector<std::pair<std::string, std::string>>{
           {"footer = [\"Z[0-50]\"]", "holds '['"},
           {"footer = [\"X[100]\"]", "holds '['"},
           {"tool_change = [\"T{tool} M6 X[5]\"]", "holds '['"},
           {"tcp_on = [\"Y[20]\"]", "holds '['"},
           {"header = [\"G10 L2 P1 R45\"]", "holds G10"},
           {"header = [\"G7\"]", "holds G7"},
           {"header = [\"G59.3\"]", "holds G59.3"},
           {"header = [\"G30\"]", "holds G30"},
           {"header = [\"G95\"]", "holds G95"},
           {"header = [\"G96 S100\"]", "holds G96"},
           {"header = [\"G90.1\"]", "holds G90.1"},
           {"header = [\"G41 D3\"]", "holds G41"},
           {"header = [\"H5\"]", "holds H5"},
           {"header = [\"(unclosed\"]", "opens a comment it does not close"},
           {"header = [\"%\"]", "holds '%'"},
           {"header = [\"M30\"]", "holds M30"},
           {"header = [\"M2\"]", "holds M2"},
           {"header = [\"#1=5\"]", "holds '#'"},
           {"header = [\"M98 P9000\"]", "holds M98"},
           {"header = [\"G65 P9000\"]", "holds G65"},
           {"header = [\"O100\"]", "holds O100"},
           {"header = [\"N10 M1\"]", "holds N10"},
           {"header = [\"F100\"]", "holds F100"},
           {"header = [\"G187 P1\"]", "holds G187"},  // Haas only
           {"header = [\"P5\"]", "holds P5"},
           {"tool_change = [\"T{tool} M333333333333333333333336\"]", "no M code"},  // fuzz
           {"tool_change = [\"T5 M6\"]", "must call the tool by"},
           {"tool_change = [\"T{tool} T5 M6\"]", "calls tool T5"},
           {"header = [\"T{tool}\"]", "only the tool_change template"},
           {"work_offset = \"G10 L20 P1 X0\"", "is no work offset code"},
           {"work_offset = \"G55 G0 X1\"", "is no work offset code"},
       }) {
    INFO(block);
    expect_error(head + block + "\n", 9, says);
  }
  // What a template may hold: machine M codes, dwell and path control, the machine's own
  // tool-change macro, work offsets.
  for (const std::string block :
       {"header = [\"M11 (C UNLOCK)\", \"G80\", \"G4 P0.5\", \"M70\"]", "tcp_on = [\"M428\"]",
        "tool_change = [\"T{tool} M6\", \"G65 P9001\", \"M98 P9002\"]",
        "work_offset = \"G54.1 P3\"", "work_offset = \"G59\"",
        "footer = [\"G91 G28 A0. C0.\", \"G90\"]"}) {
    INFO(block);
    CHECK_NOTHROW(parse_machine_toml(head + block + "\n", "m.toml"));
  }
  // Per dialect: Haas's G187, Sinumerik's words and CYCLE832, a TNC's tool call with G17.
  const std::string any =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n[gcode]\n";
  CHECK_NOTHROW(
      parse_machine_toml(any + "dialect = \"haas\"\nheader = [\"G187 P1 E0.01\"]\n", "m"));
  CHECK_NOTHROW(parse_machine_toml(any + "dialect = \"fanuc\"\nheader = [\"G5.1 Q1\", \"G8 P1\", "
                                         "\"M1\", \"G64\", \"G61.1\"]\nfooter = [\"M72\"]\n",
                                   "m"));
  // LinuxCNC: the blending is gcode.blend_tolerance_mm's, which the report states (a header's
  // G64 P50 overrode the program's G64 P0.01 Q0 unseen, a bare G64 bounds nothing); M72
  // restores only what M70 saved (rs274 aborts on a footer's M72 alone), M73 is a
  // subroutine's.
  for (const char* block : {"header = [\"G64 P50\"]", "header = [\"G64\"]", "tcp_on = [\"G61\"]",
                            "header = [\"G61.1\"]"}) {
    INFO(block);
    expect_error(any + "dialect = \"linuxcnc\"\n" + block + "\n", 9,
                 "the path blending is gcode.blend_tolerance_mm's");
  }
  expect_error(any + "dialect = \"linuxcnc\"\nfooter = [\"M72\"]\n", 9,
               "holds M72: LinuxCNC restores with M72 only a modal state M70 saved");
  expect_error(any + "dialect = \"linuxcnc\"\nheader = [\"M73\"]\n", 9, "holds M73");
  // Each dialect's own work offsets; LinuxCNC's acting comments (issue 63.12).
  CHECK_NOTHROW(parse_machine_toml(any + "dialect = \"linuxcnc\"\nwork_offset = \"G59.3\"\n", "m"));
  expect_error(any + "dialect = \"linuxcnc\"\nwork_offset = \"G54.1 P5\"\n", 9,
               "no work offset code of linuxcnc");
  expect_error(any + "dialect = \"fanuc\"\nwork_offset = \"G59.3\"\n", 9,
               "no work offset code of fanuc");
  expect_error(any + "dialect = \"linuxcnc\"\nheader = [\"(ABORT, x)\"]\n", 9,
               "holds the comment (ABORT, ...)");
  CHECK_NOTHROW(
      parse_machine_toml(any + "dialect = \"linuxcnc\"\nheader = [\"(MSG, start)\"]\n", "m"));
  CHECK_NOTHROW(
      parse_machine_toml(any + "dialect = \"siemens\"\nheader = [\"FFWON\", \"SOFT\", \"G642\", "
                               "\"CYCLE832(0.01,_ORI_FINISH,1)\", \"COMPCAD ; smooth\"]\n",
                         "m"));
  CHECK_NOTHROW(
      parse_machine_toml(any + "dialect = \"heidenhain\"\ntool_change = [\"T{tool} G17\"]\n", "m"));
  expect_error(any + "dialect = \"siemens\"\nheader = [\"TRANS X10\"]\n", 9, "holds TRANS");
  expect_error(any + "dialect = \"siemens\"\nheader = [\"CYCLE832(0.01,[1])\"]\n", 9, "holds '['");
  // Spindle, coolant, tool and program end: the read-back must know them (a machinist's review,
  // tests/test_program.cpp).
  expect_error(head + "tcp_on = [\"M5\"]\n", 9, "holds M5: the spindle, coolant");
  expect_error(head + "header = [\"S1000 M3\"]\n", 9, "holds S1000");
  expect_error(head + "footer = [\"M09\"]\n", 9, "holds M09");
  expect_error(head + "header = [\"T5\"]\n", 9, "holds T5");
  expect_error(head + "header = [\"M6\"]\n", 9, "holds M6");
  expect_error(head + "footer = [\"M30\"]\n", 9, "holds M30");
  expect_error(head + "tool_change = [\"T{tool} M6\", \"M8\"]\n", 9, "holds M8");
  expect_error(head + "tool_change = [\"T{tool} M6\", \"G20\"]\n", 9, "holds G20");
  expect_error(head + "work_offset = \"G43 H1\"\n", 9, "is no work offset code");
  expect_error(head + "header = \"M98\"\n", 9, "list of blocks");
  expect_error(head + "program_number = 10000\n", 9, "from 1 to 9999");
  expect_error(head + "end_park_xy_mm = [1e9, 0]\n", 9, "within [-1e5, 1e5] mm");
  // Finer than the written words: 1e-6 mm cut each move into 4,096 blocks (5 GB; issue 63.11).
  expect_error(head + "linearise_tolerance_mm = 1e-6\n", 9, "at least 0.001 mm");
  CHECK_NOTHROW(parse_machine_toml(head + "linearise_tolerance_mm = 0.001\n", "m"));
  // Haas's O words take five digits (issue 63.12: 10000 was refused citing Fanuc's O9999).
  const Machine haas =
      parse_machine_toml(any + "dialect = \"haas\"\nprogram_number = 10000\n", "m");
  CHECK(haas.gcode.program.number == 10000);
  expect_error(any + "dialect = \"haas\"\nprogram_number = 100000\n", 9, "(haas's O1 to O99999)");
  expect_error(head + "program_name = \"a b\"\n", 9, "letters, digits");
  expect_error(head + "coolant = \"through\"\n", 9, "\"none\", \"flood\" or \"mist\"");
  expect_error(head + "linearise_tolerance_mm = -1\n", 9, "0 (off) or at least 0.001 mm");
}

TEST_CASE(
    "machine file: [defaults] spindle speed and tool, the index threshold, the end pose and a "
    "footer that homes the rotaries",
    "[io][machine]") {
  const std::string head =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n";
  const Machine plain = parse_machine_toml(head, "m.toml");
  CHECK(!plain.default_spindle_rpm);
  CHECK(!plain.default_tool_number);
  CHECK(plain.gcode.program.index_threshold_deg == 1.0);
  CHECK(plain.gcode.program.end_pose == EndPose::Home);
  const Machine m = parse_machine_toml(
      head +
          "[defaults]\nspindle_rpm = 12000\ntool_number = 7\n[gcode]\ndialect = \"fanuc\"\n"
          "index_threshold_deg = 5\nend_pose = \"none\"\n"
          "footer = [\"G91 G28 A0. C0.\", \"G90\"]\n",
      "m.toml");
  CHECK(m.default_spindle_rpm == 12000.0);
  CHECK(m.default_tool_number == 7);
  CHECK(m.gcode.program.index_threshold_deg == 5.0);
  CHECK(m.gcode.program.end_pose == EndPose::None);
  CHECK(m.gcode.program.footer == std::vector<std::string>{"G91 G28 A0. C0.", "G90"});
  const std::string d = head + "[defaults]\n";
  expect_error(d + "spindle_rpm = 0\n", 8, "within [1, 200000] rpm");
  expect_error(d + "spindle_rpm = nan\n", 8, "must be finite");
  expect_error(d + "tool_number = 0\n", 8, "from 1 to 99999");
  expect_error(d + "tool_number = 2.5\n", 8, "from 1 to 99999");
  expect_error(d + "tool = 1\n", 8, "unknown key 'defaults.tool'");
  const std::string g = head + "[gcode]\n";
  expect_error(g + "index_threshold_deg = -1\n", 8, "within [0, 360] deg");
  // The feed ratio: 2 by default; below 1 would speed every kept block up, nan and inf mean
  // nothing.
  CHECK(plain.gcode.max_feed_ratio == 2.0);
  CHECK(parse_machine_toml(g + "max_feed_ratio = 1.5\n", "m.toml").gcode.max_feed_ratio == 1.5);
  for (const char* bad : {"0.5", "0", "-2", "101", "nan", "inf", "\"2\""}) {
    INFO(bad);
    expect_error(g + "max_feed_ratio = " + bad + "\n", 8, "gcode.max_feed_ratio must");
  }
  expect_error(g + "end_pose = \"park\"\n", 8, "\"home\" or \"none\"");
  expect_error(g + "footer = [\"G91 G28 C90.\"]\n", 8, "home the rotary axes only");
  expect_error(g + "footer = [\"G28 X0 C0\"]\n", 8, "home the rotary axes only");
  // Home outside the tilt range: no silent end pose.
  expect_error(
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = 10\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n[gcode]\n",
      7, "outside this machine's axis ranges");
  // The same without a [gcode] table: the default end pose is checked as the key would be.
  expect_error(
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = 10\nmax_deg = 90\n[axes.C]\n"
      "continuous = true\n",
      0, "gcode.end_pose \"home\" (the default) turns A and C to 0");
}

TEST_CASE("machine file: machine mode needs an explicit [pivot] -- the Haas preset has none",
          "[io][machine][bad-input]") {
  // Without [pivot] every point would be posted about pivots at 0 (a machinist's review,
  // tests/test_program.cpp).
  expect_error(replace(kFull,
                       "[pivot]\na_axis_y = 1.5\na_axis_z = -2.0\nc_axis_x = 3.0\n"
                       "c_axis_y = 4.0\n",
                       ""),
               20, "gcode.mode \"machine\" needs the machine's [pivot]");
  // Zeros said explicitly are a pivot.
  const Machine zeros = parse_machine_toml(
      replace(kFull, "a_axis_y = 1.5\na_axis_z = -2.0\nc_axis_x = 3.0\nc_axis_y = 4.0",
              "a_axis_y = 0\na_axis_z = 0\nc_axis_x = 0\nc_axis_y = 0"),
      "m.toml");
  CHECK(zeros.gcode.mode == GcodeMode::Machine);
  // The Haas preset (G234 carries the pivots the control knows): machine mode is refused.
  std::string haas =
      taxopt::test::read_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/haas-umc750.toml");
  haas = replace(haas, "mode = \"tcp\"", "mode = \"machine\"");
  CHECK_THROWS_WITH(parse_machine_toml(haas, "haas.toml"), Catch::Contains("b_axis_x, b_axis_z"));
}

TEST_CASE("machine file: a header, footer or tool change that switches TCP is refused (issue 63.6)",
          "[io][machine][bad-input]") {
  const std::string dir = std::string(TAXOPT_SOURCE_DIR) + "/data/machines/";
  // LinuxCNC's sample: its switch M428 in the header would turn TCP on before the table turns
  // and G43 H1 comes on (the order LinuxCNC's controller refuses).
  const std::string sample = taxopt::test::read_file(dir + "linuxcnc-xyzac-trt.toml");
  REQUIRE(sample.find("[gcode]\n") != std::string::npos);
  for (const char* key : {"header", "footer"}) {
    INFO(key);
    const std::string with =
        replace(sample, "[gcode]\n", "[gcode]\n" + std::string(key) + " = [\"M428\"]\n");
    CHECK_THROWS_WITH(
        parse_machine_toml(with, "m.toml"),
        Catch::Contains(std::string("gcode.") + key + " holds M428") && Catch::Contains("m.toml:"));
  }
  // A TNC's M128 likewise; other M codes stay a template's own.
  const std::string tnc =
      "kinematics = \"ac-table-table\"\n[axes.A]\nmin_deg = -90\n"
      "max_deg = 90\n[axes.C]\ncontinuous = true\n[gcode]\n"
      "dialect = \"heidenhain\"\n";
  CHECK_THROWS_WITH(parse_machine_toml(tnc + "header = [\"M128\"]\n", "t.toml"),
                    Catch::Contains("M128"));
  CHECK_NOTHROW(parse_machine_toml(tnc + "header = [\"G40\"]\n", "t.toml"));
}
