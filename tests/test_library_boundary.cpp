// The library checked at its boundary: a post-processor builds points, parts and machines in
// code, none of which a file reader has seen. Every bad value ends in an InputError naming the
// operation and point or the field, before any work -- never a crash, an out-of-bounds read, a
// silently changed point or an error after the whole optimisation. A seeded fuzzer over in-memory
// inputs holds it to that (under ASan in CI).
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// One pass of 21 points over a flat square at z = 0, a 3 mm ball, built in code.
Toolpath pass_in_code() {
  Toolpath tp;
  tp.source = "in-memory";
  Operationd op;
  op.name = "POST";
  op.tool = Tool::ball_end_mill(6.0, 20.0);
  op.tool.number = 1;
  op.tool.from_file = true;
  op.spindle_rpm = 8000.0;
  for (int i = 0; i <= 20; ++i) {
    CLPointd p;
    p.tip_mm = Vec3d(-10.0 + i, 0.0, 0.0);
    p.axis = Vec3d(0.0, std::sin(0.1 * i / 20.0), std::cos(0.1 * i / 20.0));
    p.feed_mm_per_min = 1000.0;
    p.motion = i == 0 ? Motion::Rapid : Motion::Feed;
    op.points.push_back(p);
  }
  tp.operations.push_back(op);
  return tp;
}

TriangleMesh square() {
  TriangleMesh m;
  m.vertices = {{-20, -20, 0},  {20, -20, 0},  {20, 20, 0},  {-20, 20, 0},
                {-20, -20, -5}, {20, -20, -5}, {20, 20, -5}, {-20, 20, -5}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}, {0, 4, 5}, {0, 5, 1},
             {1, 5, 6}, {1, 6, 2}, {2, 6, 7}, {2, 7, 3}, {3, 7, 4}, {3, 4, 0}};
  return m;
}

}  // namespace

TEST_CASE(
    "library boundary: every bad point built in code is an InputError naming its operation and "
    "index before any work, and a good one runs",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::Paper;
  {
    const JobResult ok = run_job(pass_in_code(), default_machine(), options);
    CHECK(ok.ok());
  }
  struct Bad {
    const char* what;
    std::function<void(CLPointd&)> change;
    const char* said;
  };
  const std::vector<Bad> bad = {
      {"an axis of length 2", [](CLPointd& p) { p.axis *= 2.0; }, "has length 2"},
      {"a NaN axis", [](CLPointd& p) { p.axis.x() = kNaN; }, "expected a unit vector"},
      {"a zero axis", [](CLPointd& p) { p.axis.setZero(); }, "has length 0"},
      {"an axis off unit by 1e-5", [](CLPointd& p) { p.axis *= 1.00001; },
       "has length 1.00001, expected a unit vector"},
      {"an infinite tip", [](CLPointd& p) { p.tip_mm.x() = kInf; }, "not a finite point"},
      {"a NaN tip", [](CLPointd& p) { p.tip_mm.z() = kNaN; }, "not a finite point"},
      {"a tip 2 km away", [](CLPointd& p) { p.tip_mm.y() = 2e6; }, "within +-1e6 mm"},
      {"a negative feed", [](CLPointd& p) { p.feed_mm_per_min = -5.0; }, "feed -5 mm/min"},
      {"a NaN feed", [](CLPointd& p) { p.feed_mm_per_min = kNaN; }, "feed nan mm/min"},
  };
  for (const Bad& b : bad) {
    INFO(b.what);
    Toolpath tp = pass_in_code();
    b.change(tp.operations[0].points[7]);
    const std::string e = input_error_of([&] { (void)run_job(tp, default_machine(), options); });
    CHECK_THAT(e, Catch::Contains("operation POST, point 7: "));
    CHECK_THAT(e, Catch::Contains(b.said));
    // A program reads where: the operation and point, and the field.
    try {
      (void)run_job(tp, default_machine(), options);
    } catch (const InputError& err) {
      CHECK(err.place().operation == std::optional<std::size_t>(0));
      CHECK(err.place().point == std::optional<std::size_t>(7));
      CHECK_THAT(err.place().field, Catch::StartsWith("CLPoint::"));
    }
  }
}

TEST_CASE(
    "library boundary: a flipped axis is said as one, with the operation and point a "
    "program reads, and a bad option names its field",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::Paper;
  Toolpath tp = pass_in_code();
  tp.operations[0].points[9].axis *= -1.0;
  try {
    (void)run_job(tp, default_machine(), options);
    FAIL("a flipped axis ran");
  } catch (const InputError& e) {
    CHECK_THAT(e.message(), Catch::Contains("operation POST, point 9: the tool axis") &&
                                Catch::Contains("points into the part") &&
                                Catch::Contains("flipped axis"));
    CHECK(e.line() == 0);
    CHECK(e.place().operation == std::optional<std::size_t>(0));
    CHECK(e.place().point == std::optional<std::size_t>(9));
    CHECK(e.place().field == "CLPoint::axis");
  }
  JobOptions bad = options;
  bad.feed_mm_per_min = -1.0;
  try {
    check_options(bad);
    FAIL("a negative feed was taken");
  } catch (const InputError& e) {
    CHECK(e.place().field == "JobOptions::feed_mm_per_min");
    CHECK_FALSE(e.place().operation);
  }
  Toolpath no_size = pass_in_code();
  no_size.operations[0].tool.diameter_mm = -6.0;
  try {
    (void)run_job(no_size, default_machine(), options);
    FAIL("a tool of diameter -6 ran");
  } catch (const InputError& e) {
    CHECK(e.place().operation == std::optional<std::size_t>(0));
    CHECK(e.place().field == "Operation::tool.diameter_mm");
  }
}

TEST_CASE(
    "library boundary: axes normalised in float (1 +- 1e-7) are the caller's directions: the "
    "job runs as on the same axes normalised in double",
    "[library]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::Paper;
  const Toolpath exact = pass_in_code();
  Toolpath floats = exact;
  for (CLPointd& p : floats.operations[0].points) {
    const Eigen::Vector3f f = p.axis.cast<float>().normalized();
    p.axis = f.cast<double>();
  }
  floats.operations[0].points[3].axis *= 1.0 + 3e-7;
  const JobResult a = run_job(exact, default_machine(), options);
  const JobResult b = run_job(floats, default_machine(), options);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  const auto& ra = a.operations.at(0).rows;
  const auto& rb = b.operations.at(0).rows;
  REQUIRE(ra.size() == rb.size());
  for (std::size_t i = 0; i < ra.size(); ++i) {
    CHECK(ra[i].tilt_axis_deg == Approx(rb[i].tilt_axis_deg).margin(1e-4));
    CHECK(ra[i].c_deg == Approx(rb[i].c_deg).margin(1e-4));
  }
}

TEST_CASE(
    "library boundary: a tool built in code is range-checked as the CL reader checks one -- a "
    "size that is negative, not finite or beyond 1000 mm, or a described tool with no diameter, "
    "is an InputError naming the operation and field before any work",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::Paper;
  struct Bad {
    const char* what;
    std::function<void(Tool&)> change;
    const char* said;
  };
  const std::vector<Bad> bad = {
      {"no diameter", [](Tool& t) { t.diameter_mm = 0.0; }, "from_file says the tool is described"},
      {"a negative diameter", [](Tool& t) { t.diameter_mm = -6.0; }, "tool.diameter_mm -6"},
      {"a negative diameter, not described",
       [](Tool& t) {
         t.diameter_mm = -6.0;
         t.from_file = false;
       },
       "tool.diameter_mm -6"},
      {"a NaN diameter", [](Tool& t) { t.diameter_mm = kNaN; }, "tool.diameter_mm nan"},
      {"a 2 m flute", [](Tool& t) { t.flute_length_mm = 2000.0; }, "tool.flute_length_mm 2000"},
      {"a negative corner", [](Tool& t) { t.corner_radius_mm = -1.0; }, "corner_radius_mm -1"},
      {"a corner beyond the radius", [](Tool& t) { t.corner_radius_mm = 4.0; },
       "exceeds half the diameter"},
      {"an infinite gauge", [](Tool& t) { t.gauge_length_mm = kInf; }, "gauge_length_mm inf"},
      {"a taper of 90 deg", [](Tool& t) { t.taper_rad = 2.0; }, "taper_rad 2"},
  };
  for (const Bad& b : bad) {
    INFO(b.what);
    Toolpath tp = pass_in_code();
    b.change(tp.operations[0].tool);
    const std::string e = input_error_of([&] { (void)run_job(tp, default_machine(), options); });
    CHECK_THAT(e, Catch::Contains("operation POST: Operation::tool."));
    CHECK_THAT(e, Catch::Contains(b.said));
  }
}

TEST_CASE(
    "library boundary: one deviation cone per run -- a cone given where run_job does not read "
    "it is refused naming the field to set",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::Global;
  options.global.max_deviation_deg = 10.0;
  CHECK_THAT(input_error_of([&] { (void)run_job(pass_in_code(), default_machine(), options); }),
             Catch::Contains("JobOptions::global.max_deviation_deg is not read by run_job"));
  // The run's cone, set where it is read, bounds every written axis.
  options.global = GlobalOptions{};
  options.max_deviation_deg = 10.0;
  const Toolpath tp = pass_in_code();
  const JobResult r = run_job(tp, default_machine(), options);
  REQUIRE(r.ok());
  for (std::size_t i = 0; i < r.operations[0].rows.size(); ++i) {
    CHECK(rad_to_deg(angle_between(r.operations[0].rows[i].axis,
                                   tp.operations[0].points[i].axis)) <= 10.0 + 1e-6);
  }
}

TEST_CASE(
    "library boundary: no point to post is an InputError, and a feed point 50 mm above the part "
    "mid-pass is a finding naming it",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::None;
  Toolpath none = pass_in_code();
  none.operations.clear();
  CHECK_THAT(input_error_of([&] { (void)run_job(none, default_machine(), options); }),
             Catch::Contains("no CL point in any operation"));
  Toolpath empty = pass_in_code();
  empty.operations[0].points.clear();
  CHECK_THAT(input_error_of([&] { (void)run_job(empty, default_machine(), options); }),
             Catch::Contains("nothing to post"));
  // The untouched pass: every feed point on the part.
  CHECK_FALSE(run_job(pass_in_code(), default_machine(), options).has(FindingCode::FeedInAir));
  Toolpath lifted = pass_in_code();
  lifted.operations[0].points[10].tip_mm.z() += 50.0;
  const JobResult r = run_job(lifted, default_machine(), options);
  REQUIRE(r.has(FindingCode::FeedInAir));
  for (const Finding& f : r.findings) {
    if (f.code != FindingCode::FeedInAir) continue;
    CHECK(f.severity == Severity::Warning);
    CHECK_THAT(f.message, Catch::Contains("1 feed points in the air"));
    CHECK_THAT(f.message, Catch::Contains("the ball up to 49.9963 mm off it (point 10)"));
  }
}

TEST_CASE("library boundary: a mesh built in code is checked before anything reads it",
          "[library][bad-input]") {
  {
    TriangleMesh m = square();
    m.faces[3] = {0, 99999, 2};  // valgrind saw Part read past the vertices here
    CHECK_THAT(input_error_of([&] { Part p(m); }),
               Catch::Contains("Part: face 3 names vertex 99999 of 8"));
  }
  {
    TriangleMesh m = square();
    m.faces[0] = {0, -1, 2};
    CHECK_THAT(input_error_of([&] { Part p(m); }), Catch::Contains("face 0 names vertex -1"));
  }
  {
    TriangleMesh m = square();
    m.vertices[5].y() = kNaN;  // FCL printed "too many iterations in Jacobi transform"
    CHECK_THAT(input_error_of([&] { Part p(m); }),
               Catch::Contains("Part: vertex 5 is not a finite point"));
  }
  CHECK_THAT(input_error_of([&] { Part p(TriangleMesh{}); }),
             Catch::Contains("the mesh has no faces"));
}

TEST_CASE(
    "library boundary: a machine built in code is checked as a machine file is, naming the "
    "field, before the optimisation",
    "[library][bad-input][machine]") {
  struct Bad {
    const char* what;
    std::function<void(Machine&)> change;
    const char* said;
  };
  const std::vector<Bad> bad = {
      {"A min above max",
       [](Machine& m) {
         m.rotary.tilt.min_rad = 1.0;
         m.rotary.tilt.max_rad = -1.0;
       },
       "Machine::rotary.tilt.min_rad must be <= max_rad"},
      {"a NaN C limit",
       [](Machine& m) {
         m.rotary.c.continuous = false;
         m.rotary.c.max_rad = kNaN;
       },
       "Machine::rotary.c.max_rad must be a number"},
      {"a holder clearance of a metre", [](Machine& m) { m.holder_clearance_mm = 1000.0; },
       "Machine::holder_clearance_mm must be within [0, 50]"},
      {"a NaN holder radius", [](Machine& m) { m.holder_radius_mm = kNaN; },
       "Machine::holder_radius_mm must be within (0, 1000]"},
      {"a NaN velocity limit", [](Machine& m) { m.limits[3].max_velocity_per_s = kNaN; },
       "Machine::limits[3].max_velocity_per_s must be finite and >= 0 (the A joint)"},
      {"a negative acceleration", [](Machine& m) { m.limits[0].max_accel_per_s2 = -1.0; },
       "Machine::limits[0].max_accel_per_s2"},
      {"Fanuc with 9 decimals",
       [](Machine& m) {
         m.gcode.dialect = GcodeDialect::Fanuc;
         m.gcode.decimals = 9;
       },
       "Machine::gcode.decimals must be within [0, 4] (the most fanuc takes)"},
      {"Heidenhain with G93",
       [](Machine& m) {
         m.gcode.dialect = GcodeDialect::Heidenhain;
         m.gcode.feed_mode = FeedMode::InverseTime;
       },
       "not written for the heidenhain dialect"},
      {"a free kinematics label", [](Machine& m) { m.kinematics = "head-table"; },
       "Machine::kinematics 'head-table' does not name this machine"},
      {"B tilt named A/C", [](Machine& m) { m.rotary.tilt_about = TiltAxis::Y; },
       "\"bc-table-table\" for a tilt about Y"},
      {"a sense of 0", [](Machine& m) { m.rotary.c.sense = 0; }, "Machine::rotary.c.sense"},
      {"a feed ratio below 1", [](Machine& m) { m.gcode.max_feed_ratio = 0.5; },
       "Machine::gcode.max_feed_ratio"},
      {"a park outside the travel",
       [](Machine& m) {
         m.linear_range[0].max_mm = 100.0;
         m.gcode.program.end_park_xy_mm = std::array<double, 2>{200.0, 0.0};
       },
       "Machine::gcode.program.end_park_xy_mm[0]"},
      {"a linearisation finer than the written words",
       [](Machine& m) { m.gcode.program.linearise_tolerance_mm = 1e-6; },
       "Machine::gcode.program.linearise_tolerance_mm"},
  };
  for (const Bad& b : bad) {
    INFO(b.what);
    Machine m = default_machine();
    b.change(m);
    CHECK_THAT(input_error_of([&] { validate(m); }), Catch::Contains(b.said));
    // run_job refuses it before any work, even with nothing to do.
    JobOptions options;
    options.method = Method::Global;
    CHECK_THAT(input_error_of([&] { (void)run_job(pass_in_code(), m, options); }),
               Catch::Contains(b.said));
  }
  CHECK_NOTHROW(validate(default_machine()));
}

TEST_CASE(
    "library boundary: fuzzed in-memory points, meshes and machines end in a result or an "
    "InputError, and a point is never posted other than it was given",
    "[library][bad-input][fuzz]") {
  std::mt19937 rng(4646);
  std::uniform_int_distribution<int> pick(0, 11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double specials[] = {kNaN, kInf, -kInf, 0.0, -0.0, 1e308, -1e308, 1e-308, 2.0, 1.0};
  const auto special = [&] { return specials[static_cast<std::size_t>(pick(rng)) % 10]; };
  int results = 0, refusals = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Toolpath tp = pass_in_code();
    TriangleMesh mesh = square();
    Machine machine = default_machine();
    for (int k = 0; k < 1 + trial % 3; ++k) {
      CLPointd& p = tp.operations[0].points[static_cast<std::size_t>(pick(rng)) % 21];
      switch (pick(rng) % 6) {
        case 0: p.tip_mm[pick(rng) % 3] = special(); break;
        case 1: p.axis[pick(rng) % 3] = special(); break;
        case 2: p.feed_mm_per_min = special(); break;
        case 3:
          mesh.vertices[static_cast<std::size_t>(pick(rng)) % 8][pick(rng) % 3] = special();
          break;
        case 4:
          mesh.faces[static_cast<std::size_t>(pick(rng))][pick(rng) % 3] =
              static_cast<int>(1e4 * u(rng));
          break;
        default:
          machine.limits[static_cast<std::size_t>(pick(rng)) % 5].max_accel_per_s2 = special();
      }
    }
    INFO("trial " << trial);
    try {
      const Part part(mesh);
      JobOptions options;
      options.part = &part;
      options.method = trial % 2 ? Method::Paper : Method::None;
      const JobResult r = run_job(tp, machine, options);
      ++results;
      // What was written is what was given: every point's tip read back within the rounding.
      if (r.ok()) {
        const std::vector<GcodeMove> moves = read_gcode_moves(r.gcode.text, "fuzz.ngc");
        for (std::size_t i = 0; i < tp.operations[0].points.size(); ++i) {
          const int line = r.gcode.emitted[0][i];
          if (line <= 0) continue;
          for (const GcodeMove& m : moves) {
            if (m.line == line && options.method == Method::None) {
              CHECK((m.xyz_mm - tp.operations[0].points[i].tip_mm).norm() < 1e-3);
            }
          }
        }
      }
    } catch (const InputError&) {
      ++refusals;
    }
  }
  CHECK(results > 0);
  CHECK(refusals > 0);
}

TEST_CASE(
    "library boundary: a program template built in code is held to the machine file's rules "
    "(a header that moves the tool would be written and never checked)",
    "[library][bad-input]") {
  const Part part(square());
  JobOptions options;
  options.part = &part;
  options.method = Method::None;
  const Toolpath tp = pass_in_code();
  const auto refusal = [&](const Machine& m) {
    return input_error_of([&] { (void)run_job(tp, m, options); });
  };
  {
    Machine m = default_machine();
    m.gcode.program.header = {"G0 X10 Y10 Z-2"};  // through the part, unseen by the read-back
    const std::string why = refusal(m);
    CHECK_THAT(why, Catch::Contains("gcode.header") && Catch::Contains("holds G0"));
  }
  {
    Machine m = default_machine();
    m.gcode.program.footer = {"M30"};  // the program end is taxopt's
    CHECK_THAT(refusal(m), Catch::Contains("gcode.footer"));
  }
  {
    Machine m = default_machine();
    m.gcode.program.tool_change = {"M6"};  // calls no tool: the program's tool is not known
    CHECK_THAT(refusal(m), Catch::Contains("gcode.tool_change") && Catch::Contains("{tool}"));
  }
  {
    Machine m = default_machine();
    m.gcode.program.work_offset = "G10 L2 P1 X0";
    CHECK_THAT(refusal(m), Catch::Contains("gcode.work_offset"));
  }
  {
    // A TNC writes the name into its begin block: a line break there would start a block.
    Machine m = default_machine();
    m.gcode.dialect = GcodeDialect::Heidenhain;
    m.gcode.decimals = 4;
    m.gcode.program.name = "PART\nG00 Z-50";
    CHECK_THAT(refusal(m), Catch::Contains("gcode.program.name"));
  }
  {
    // A template of the dialect's own words runs, and is written as it is.
    Machine m = default_machine();
    m.gcode.program.header = {"M64 P0"};
    m.gcode.program.tool_change = {"T{tool} M6", "G43 H{tool}"};
    const std::string why = refusal(m);
    INFO(why);
    CHECK_THAT(why, Catch::Contains("gcode.tool_change"));  // an H offset is taxopt's
    m.gcode.program.tool_change = {"T{tool} M6"};
    const JobResult r = run_job(tp, m, options);
    CHECK(r.ok());
    CHECK(r.gcode.text.find("M64 P0") != std::string::npos);
  }
}
