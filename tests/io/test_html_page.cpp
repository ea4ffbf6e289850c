#include <sys/stat.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support.hpp"
#include "support/html_page.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

/// The page's data: the JSON of its `taxopt-data` script element.
nlohmann::json page_data(const std::string& page) {
  const std::string open = "<script type=\"application/json\" id=\"taxopt-data\">";
  const std::size_t at = page.find(open);
  REQUIRE(at != std::string::npos);
  const std::size_t start = at + open.size();
  return nlohmann::json::parse(page.substr(start, page.find("</script>", start) - start));
}

HtmlAssets tiny_assets() {
  HtmlAssets a;
  a.three_js = "var THREE = {};";
  a.orbit_controls_js = "/* orbit */";
  a.dygraph_js = "var Dygraph = function () {};";
  a.dygraph_css = ".dygraph-legend { }";
  return a;
}

}  // namespace

TEST_CASE("html page: a mesh over the budget is clustered within it, without collapsed triangles",
          "[html]") {
  Heightfield hf = wall_heightfield();
  const TriangleMesh mesh = heightfield_mesh(hf, 0.25, -20.0, 40.0, -10.0, 50.0);
  REQUIRE(mesh.faces.size() > 100000);
  double cell = -1.0;
  const TriangleMesh small = decimate_mesh(mesh, 5000, &cell);
  CHECK(small.faces.size() <= 5000);
  CHECK(small.faces.size() > 500);  // not emptied: the budget is used
  CHECK(cell > 0.25);
  Vec3d lo = mesh.vertices.front(), hi = lo;
  for (const Vec3d& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  for (const auto& f : small.faces) {
    CHECK((f[0] != f[1] && f[1] != f[2] && f[0] != f[2]));
    for (int q : f) {
      REQUIRE(q >= 0);
      REQUIRE(static_cast<std::size_t>(q) < small.vertices.size());
    }
  }
  for (const Vec3d& v : small.vertices) {
    CHECK(((v - lo).minCoeff() >= -1e-9 && (hi - v).minCoeff() >= -1e-9));
  }
  // Within the budget: the mesh itself.
  const TriangleMesh same = decimate_mesh(mesh, mesh.faces.size(), &cell);
  CHECK(same.faces.size() == mesh.faces.size());
  CHECK(cell == 0.0);
}

TEST_CASE("html page: missing libraries are refused by name, and one that would end its element",
          "[html]") {
  TempDir t;
  try {
    load_html_assets(t.dir());
    FAIL("no InputError");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("three/three.min.js"));
    CHECK_THAT(e.what(), Catch::Contains("libjs-three"));
  }
  JobResult result;
  HtmlAssets bad = tiny_assets();
  bad.dygraph_js = "var s = '</SCRIPT>';";
  CHECK_THROWS_AS(html_page(result, Toolpath{}, Machine{}, JobOptions{}, RunInfo{}, nullptr, bad),
                  InputError);
}

TEST_CASE(
    "html page: every point where a check fired is a marker, with the CSV's findings, and "
    "a message cannot end the data early",
    "[html][cli]") {
  TempDir t;
  const Heightfield hf = wall_heightfield();
  write_file(t.path("in.cls"), raster_cl(hf, 3.0, 0.0, 2, 1.0, 17.0, 17.0, 0.0, 20.0).text);
  write_file(t.path("part.stl"),
             format_stl_binary(heightfield_mesh(hf, 0.25, -10.0, 30.0, 0.0, 40.0)));
  const RunResult r = run_taxopt(
      "--in " + t.path("in.cls") + " --part " + t.path("part.stl") +
      " --method none --force -q --holder-radius 14 --holder-length 10 --flute-length 6 "
      "--gauge-length 15 "
      "--report " +
      t.path("r.json") + " --points-csv " + t.path("p.csv") + " --html " + t.path("p.html"));
  INFO(r.err);
  REQUIRE(r.code == 1);  // the holder hits the wall
  const auto report = nlohmann::json::parse(read_file(t.path("r.json")));
  long colliding = 0, moves = 0;
  std::size_t points = 0;
  for (const auto& op : report["operations"]) {
    colliding += op["after"]["colliding_points"].get<long>();
    moves += op["verification"]["colliding_moves"].get<long>();
    points += op["points"].get<std::size_t>();
  }
  REQUIRE(colliding > 0);
  // The CSV: one `findings` cell per row, the marks by name.
  std::istringstream csv(read_file(t.path("p.csv")));
  std::string line;
  std::getline(csv, line);
  CHECK_THAT(line, Catch::Contains(",cl_line,findings,"));
  // The cells of a row (no operation name here holds a comma), and the two columns by name.
  const auto cells = [](const std::string& row) {
    std::vector<std::string> out;
    std::istringstream in(row);
    for (std::string cell; std::getline(in, cell, ',');) out.push_back(cell);
    if (!row.empty() && row.back() == ',') out.emplace_back();
    return out;
  };
  const std::vector<std::string> header = cells(line);
  const auto column = [&](const char* name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t findings_at = column("findings"), line_at = column("cl_line");
  REQUIRE(findings_at < header.size());
  long csv_points = 0, csv_moves = 0, rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    const std::vector<std::string> row = cells(line);
    REQUIRE(row.size() == header.size());
    const std::string& findings = row[findings_at];
    csv_points += findings.find("point_collision") != std::string::npos ||
                  findings.find("flute_gouge") != std::string::npos;
    csv_moves += findings.find("move_collision") != std::string::npos;
    CHECK(std::stoi(row[line_at]) > 0);  // the CL line
  }
  CHECK(static_cast<std::size_t>(rows) == points);
  CHECK(csv_points == colliding);
  CHECK(csv_moves == moves);
  // The page: the same points as markers, every one with its CL line.
  const std::string page = read_file(t.path("p.html"));
  const nlohmann::json data = page_data(page);
  long page_points = 0, page_moves = 0;
  for (const auto& m : data["markers"]) {
    const std::string marks = m["marks"];
    page_points += marks.find("point_collision") != std::string::npos ||
                   marks.find("flute_gouge") != std::string::npos;
    page_moves += marks.find("move_collision") != std::string::npos;
    CHECK(m["line"].get<int>() > 0);
  }
  CHECK(page_points == colliding);
  CHECK(page_moves == moves);
  CHECK(data["points"].get<std::size_t>() == points);
  CHECK(data["collision_checked"].get<bool>());
  // The libraries are in the page, nothing is loaded from elsewhere.
  CHECK(count_of(page, "<script src") == 0);
  CHECK(count_of(page, "OrbitControls") > 0);
  CHECK(count_of(page, "Dygraph") > 0);

  // A finding whose message holds "</script>" (a CL file's operation name can) stays inside
  // the data element, and the header shows it escaped.
  JobResult result;
  result.operations.emplace_back();
  result.operations.back().name = "</script><b>op";
  result.operations.back().rows.resize(3);
  result.operations.back().rows[1].mark(PointMark::CFlip);
  result.findings.push_back(
      {FindingCode::PointCollision, Severity::Problem, 0, 7, "at </script> line 7 <!--", {}});
  result.problems.push_back("at </script> line 7 <!--");
  const std::string hostile =
      html_page(result, Toolpath{}, Machine{}, JobOptions{}, RunInfo{}, nullptr, tiny_assets());
  const nlohmann::json d = page_data(hostile);
  CHECK(d["findings"][0]["message"] == "at </script> line 7 <!--");
  CHECK(d["operations"][0]["name"] == "</script><b>op");
  CHECK(d["markers"].size() == 1);
  CHECK(count_of(hostile, "<b>op") == 0);
  CHECK(count_of(hostile, "&lt;/script&gt;") > 0);
}

TEST_CASE(
    "html page: the summary shows each rotary axis's peaks, before and after, under the "
    "machine's letters -- a tilt axis that rises is not hidden by a combined figure that falls",
    "[html]") {
  JobResult result;
  result.tilt_letter = 'B';
  result.operations.emplace_back();
  OperationResult& op = result.operations.back();
  op.name = "FILLET";
  op.before.max_accel_deg_s2 = 500.0;
  op.after.max_accel_deg_s2 = 200.0;
  op.before.tilt.max_accel_deg_s2 = 11.25;
  op.after.tilt.max_accel_deg_s2 = 52.5;
  op.before.c.max_accel_deg_s2 = 499.0;
  op.after.c.max_accel_deg_s2 = 190.0;
  op.before.tilt.max_omega_deg_s = 1.5;
  op.after.tilt.max_omega_deg_s = 2.25;
  const std::string page =
      html_page(result, Toolpath{}, Machine{}, JobOptions{}, RunInfo{}, nullptr, tiny_assets());
  const std::size_t table = page.find("<table class=\"summary\">");
  REQUIRE(table != std::string::npos);
  const std::string t = page.substr(table, page.find("</table>", table) - table);
  CHECK_THAT(t, Catch::Contains("peak &omega; B deg/s") && Catch::Contains("peak a B deg/s") &&
                    Catch::Contains("peak a C deg/s"));
  CHECK_THAT(t, Catch::Contains("11.2 &rarr; 52.5") || Catch::Contains("11.3 &rarr; 52.5"));
  CHECK_THAT(t, Catch::Contains("499.0 &rarr; 190.0"));
  CHECK_THAT(t, Catch::Contains("1.50 &rarr; 2.25"));
  // No machine limits: the combined peak a, said as such.
  CHECK_THAT(t, Catch::Contains("(combined a) 500.0 &rarr; 200.0"));
}

TEST_CASE("html page: over the budget the plots keep every stride's peaks and say how they thin",
          "[html]") {
  JobResult result;
  result.operations.emplace_back();
  OperationResult& op = result.operations.back();
  const std::size_t n = 5000;
  op.rows.resize(n);
  double peak = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    PointRow& p = op.rows[i];
    p.index = i;
    p.arc_mm = 0.5 * static_cast<double>(i);
    p.accel_deg_s2 = 10.0 + 5.0 * std::sin(0.37 * static_cast<double>(i));
    if (i == 2345) p.accel_deg_s2 = 987.654;  // a lone spike between the strides' first points
    p.omega_before_deg_s = (i == 4321) ? 77.0 : 1.0;
    peak = std::max(peak, p.accel_deg_s2);
  }
  HtmlBudget budget;
  budget.max_plot_points = 5000;  // 5 points a stride at most: stride 5 at 5000 points
  budget.max_axes = 100;
  const nlohmann::json d = page_data(html_page(result, Toolpath{}, Machine{}, JobOptions{},
                                               RunInfo{}, nullptr, tiny_assets(), budget));
  const auto& o = d["operations"][0];
  CHECK(d["decimation"]["plot_stride"].get<std::size_t>() == 5);
  CHECK(o["idx"].size() < n / 2);
  double shown_peak = 0.0, shown_omega = 0.0;
  for (const auto& v : o["accel_after"]) shown_peak = std::max(shown_peak, v.get<double>());
  for (const auto& v : o["omega_before"]) shown_omega = std::max(shown_omega, v.get<double>());
  CHECK(shown_peak == Approx(peak).margin(1e-3));
  CHECK(shown_omega == Approx(77.0));
  CHECK(o["axes"].size() == n / 50);
  // The x of the plots never runs back.
  double last = -1.0;
  for (const auto& v : o["arc_mm"]) {
    CHECK(v.get<double>() >= last);
    last = v.get<double>();
  }
}

TEST_CASE(
    "html page: --html refuses a folder, an alias of another file and missing libraries "
    "before any work, and writes nothing",
    "[html][cli]") {
  TempDir t;
  const std::string in = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls";
  RunResult r = run_taxopt("--in " + in + " --html " + t.dir() + " -q");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("is a folder"));
  r = run_taxopt("--in " + in + " --html " + t.path("o.nc") + " --gcode " + t.path("o.nc") + " -q");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--html and --gcode name the same file"));
  r = run_taxopt("--in " + in + " --html " + in + " -q");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("is the input file"));
  // The child inherits this process's environment (each ctest runs its own process).
  ::setenv("TAXOPT_JAVASCRIPT_DIR", t.path("nowhere").c_str(), 1);
  r = run_taxopt("--in " + in + " --html " + t.path("p.html") + " --gcode " + t.path("p.nc") +
                 " -q");
  ::unsetenv("TAXOPT_JAVASCRIPT_DIR");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("three/three.min.js"));
  CHECK_FALSE(file_exists(t.path("p.html")));
  CHECK_FALSE(file_exists(t.path("p.nc")));
  // A FIFO where a library should be: refused at once, never waited on (it blocked --html
  // forever; issue 63.11).
  const std::string js = t.path("js");
  std::filesystem::create_directories(js + "/three");
  REQUIRE(::mkfifo((js + "/three/three.min.js").c_str(), 0600) == 0);
  ::setenv("TAXOPT_JAVASCRIPT_DIR", js.c_str(), 1);
  r = run_taxopt("--in " + in + " --html " + t.path("p.html") + " -q");
  ::unsetenv("TAXOPT_JAVASCRIPT_DIR");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("not a regular file"));
  CHECK_FALSE(file_exists(t.path("p.html")));
}
