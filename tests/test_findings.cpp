// Structured outcomes: a library caller tells the kinds of finding apart by code,
// the display lists hold the same messages, and the report carries the codes.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// Every finding's message is in the display list of its severity, in order, and nothing else.
void check_lists(const JobResult& r) {
  std::vector<std::string> problems, safety, warnings;
  for (const Finding& f : r.findings) {
    (f.severity == Severity::Problem  ? problems
     : f.severity == Severity::Safety ? safety
                                      : warnings)
        .push_back(f.message);
  }
  CHECK(problems == r.problems);
  CHECK(safety == r.safety_warnings);
  CHECK(warnings == r.warnings);
  CHECK(r.ok() == problems.empty());
}

}  // namespace

TEST_CASE(
    "findings: a caller tells no part, an unreachable pose and a dynamic limit apart by "
    "code, with the operation and the CL line",
    "[findings][io][slow]") {
  std::mt19937 rng(2027);
  const Heightfield hf = random_heightfields(rng).front();
  const GeneratedCl g = raster_cl(hf, 3.0, 20.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  const Toolpath tp = parse_cl(g.text, "f.cls");

  // No part: a safety finding, and the output is still ok.
  JobOptions options;
  options.method = Method::None;
  const JobResult plain = run_job(tp, default_machine(), options);
  CHECK(plain.ok());
  CHECK(plain.has(FindingCode::NoPart));
  CHECK_FALSE(plain.has(FindingCode::UnreachablePose));
  check_lists(plain);

  // A tilt range the 20 deg axes cannot reach: a problem at the first point that fails.
  Machine narrow = default_machine();
  narrow.rotary.tilt.min_rad = deg_to_rad(-5.0);
  narrow.rotary.tilt.max_rad = deg_to_rad(5.0);
  const JobResult out = run_job(tp, narrow, options);
  CHECK_FALSE(out.ok());
  REQUIRE(out.has(FindingCode::UnreachablePose));
  for (const Finding& f : out.findings) {
    if (f.code != FindingCode::UnreachablePose) continue;
    CHECK(f.severity == Severity::Problem);
    REQUIRE(f.operation);
    CHECK(*f.operation == 0);
    CHECK(f.line > 0);
    CHECK(f.message.find("f.cls:" + std::to_string(f.line)) != std::string::npos);
  }
  check_lists(out);

  // A slow rotary table at the programmed feed: velocity or acceleration above the limit.
  Machine slow = default_machine();
  slow.limits[static_cast<std::size_t>(Joint::Tilt)] = {0.5, 1.0, 0.0};
  slow.limits[static_cast<std::size_t>(Joint::C)] = {0.5, 1.0, 0.0};
  options.method = Method::Paper;
  options.max_deviation_deg = 5.0;
  const JobResult limited = run_job(tp, slow, options);
  CHECK(limited.has(FindingCode::DynamicLimitExceeded));
  check_lists(limited);

  // The report carries the codes, severities, operations and lines.
  const auto rep = nlohmann::json::parse(report_json(out, tp, narrow, options));
  REQUIRE(rep["findings"].size() == out.findings.size());
  bool seen = false;
  for (const auto& f : rep["findings"]) {
    if (f["code"] != "unreachable_pose") continue;
    seen = true;
    CHECK(f["severity"] == "problem");
    CHECK(f["operation"] == tp.operations[0].name);
    CHECK(f["line"].get<int>() > 0);
  }
  CHECK(seen);
}

TEST_CASE(
    "units: the library puts an inch or mm part mesh and inch tool dimensions in mm, and "
    "moves the part into the MSYS frame the points were moved into",
    "[units][msys][io]") {
  TriangleMesh inch_mesh;
  inch_mesh.vertices = {Vec3d(1.0, 2.0, 0.5), Vec3d(2.0, 2.0, 0.5), Vec3d(1.0, 3.0, 0.5)};
  inch_mesh.faces = {{0, 1, 2}};
  TriangleMesh mm_mesh = inch_mesh;
  for (Vec3d& v : mm_mesh.vertices) v *= 25.4;
  Toolpath tp;
  tp.source = "u.cls";
  tp.units = LengthUnit::Inch;
  // No frame: the mesh in either unit lands in the same place, in mm.
  const TriangleMesh a = part_mesh_for(tp, inch_mesh, LengthUnit::Inch);
  const TriangleMesh b = part_mesh_for(tp, mm_mesh, LengthUnit::Millimetre);
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    CHECK((a.vertices[i] - b.vertices[i]).norm() < 1e-12);
    CHECK((a.vertices[i] - 25.4 * inch_mesh.vertices[i]).norm() < 1e-12);
  }
  // An applied MSYS frame (origin (3, 3, 0) in, turned a quarter about z): the mesh moves into
  // it as the points did, p' = R^T (p - o).
  ClFrame f;
  f.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  f.origin_mm = Vec3d(3.0, 3.0, 0.0) * 25.4;
  f.line = 3;
  tp.frames = {f};
  const TriangleMesh moved = part_mesh_for(tp, inch_mesh, LengthUnit::Inch);
  for (std::size_t i = 0; i < moved.vertices.size(); ++i) {
    const Vec3d want = f.rotation.transpose() * (25.4 * inch_mesh.vertices[i] - f.origin_mm);
    CHECK((moved.vertices[i] - want).norm() < 1e-9);
  }
  // Two frames: no one mesh fits both.
  ClFrame g = f;
  g.origin_mm.x() += 1.0;
  g.line = 40;
  tp.frames = {f, g};
  CHECK_THROWS_WITH(part_mesh_for(tp, inch_mesh, LengthUnit::Inch),
                    Catch::Contains("lines 3 and 40"));
  // Tool dimensions in the CL file's inches.
  ToolDimensions d;
  d.units = LengthUnit::Inch;
  d.ball_radius = 0.125;
  d.holder_radius = 0.75;
  const ToolOverrides o = tool_overrides(d);
  CHECK(*o.ball_radius_mm == Approx(3.175));
  CHECK(*o.holder_radius_mm == Approx(19.05));
  CHECK_FALSE(o.shank_radius_mm);
  // Converted as given; the job's check names the field a bad one is in (in mm).
  d.gauge_length = -1.0;
  JobOptions options;
  options.tool = tool_overrides(d);
  CHECK(*options.tool.gauge_length_mm == Approx(-25.4));
  CHECK_THROWS_WITH(check_options(options),
                    "JobOptions::tool.gauge_length_mm must be within (0, 1000] mm, got -25.4");
  options.option_names = {{"JobOptions::tool.gauge_length_mm", "--gauge-length"}};
  CHECK_THROWS_WITH(check_options(options),
                    "--gauge-length must be within (0, 1000] mm, got -25.4");
}

TEST_CASE("units: a part mesh in the other unit is refused naming --part-units, which posts it",
          "[units][bad-input][cli]") {
  TempDir t;
  REQUIRE(run_taxopt("generate --surface plane --width 20 --length 40 --out-cls " +
                     t.path("p.cls") + " --out-mesh " + t.path("p.stl"))
              .code == 0);
  // The same part written in inches: the run reading it in the CL file's mm finds a part a
  // 25th of its size, a few points near its origin touching it.
  const TriangleMesh mm = read_mesh_file(t.path("p.stl"));
  std::ostringstream stl;
  stl << "solid inches\n";
  for (const auto& f : mm.faces) {
    stl << "facet normal 0 0 0\nouter loop\n";
    for (int k = 0; k < 3; ++k) {
      const Vec3d v = mm.vertices[static_cast<std::size_t>(f[static_cast<std::size_t>(k)])] / 25.4;
      stl << "vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    }
    stl << "endloop\nendfacet\n";
  }
  stl << "endsolid inches\n";
  write_file(t.path("in.stl"), stl.str());
  const std::string args = "--in " + t.path("p.cls") + " --part " + t.path("in.stl") + " --gcode " +
                           t.path("o.nc") + " -q";
  const auto wrong = run_taxopt(args);
  CHECK(wrong.code == 2);
  CHECK_THAT(wrong.err, Catch::Contains("feed points touch the part") &&
                            Catch::Contains("the part in inches read as mm? (--part-units in"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  const auto right = run_taxopt(args + " --part-units in");
  INFO(right.err);
  CHECK(right.code == 0);
}

TEST_CASE(
    "units: a mesh that fits both of an MSYS's frames alike is refused, the frame given "
    "takes it",
    "[units][msys][io]") {
  // NX's MCS 30 mm along X of absolute, the points posted in it; a floor wide enough to lie
  // under them either way: the ball touches it at every sample in both frames.
  std::ostringstream cl;
  cl << "TOOL PATH/FLOOR,TOOL,BALL6\nTLDATA/MILL,6.0000,3.0000,40.0000,0.0000,0.0000\n"
        "MSYS/30.0,0.0,0.0,1.0,0.0,0.0,0.0,1.0,0.0\nFEDRAT/MMPM,500\n";
  for (int k = 0; k <= 20; ++k) cl << "GOTO/" << k << ".0,5.0,0.0,0.0,0.0,1.0\n";
  cl << "END-OF-PATH\n";
  const Toolpath tp = parse_cl(cl.str(), "f.cls");
  REQUIRE(tp.declared_frames.size() == 1);
  TriangleMesh floor;
  floor.vertices = {Vec3d(-100, -100, 0), Vec3d(100, -100, 0), Vec3d(100, 100, 0),
                    Vec3d(-100, 100, 0)};
  floor.faces = {{0, 1, 2}, {0, 2, 3}};
  CHECK_THAT(input_error_of([&] { part_mesh_for(tp, floor, LengthUnit::Millimetre); }),
             Catch::Contains("fits both frames alike") && Catch::Contains("--part-frame"));
  std::string note;
  const TriangleMesh mcs = part_mesh_for(tp, floor, LengthUnit::Millimetre, MeshFrame::Mcs, &note);
  CHECK((mcs.vertices[0] - floor.vertices[0]).norm() < 1e-12);
  CHECK_THAT(note, Catch::Contains("as asked"));
  const TriangleMesh moved =
      part_mesh_for(tp, floor, LengthUnit::Millimetre, MeshFrame::Absolute, &note);
  CHECK((moved.vertices[0] - Vec3d(-130, -100, 0)).norm() < 1e-12);
}
