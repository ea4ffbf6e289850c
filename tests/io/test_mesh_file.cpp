#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/geometry/surface.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"
#include "taxopt/io/mesh_file.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

void expect_mesh_error(const std::string& path, const std::string& says) {
  try {
    read_mesh_file(path);
    FAIL("accepted " << path);
  } catch (const InputError& e) {
    CHECK(e.file() == path);
    CHECK_THAT(e.message(), Catch::Contains(says));
  }
}

const char* kTetraOff =
    "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

}  // namespace

TEST_CASE("mesh: every format reads to the same indexed mesh", "[io][mesh]") {
  TempDir t;
  write_file(t.path("a.off"), kTetraOff);
  write_file(t.path("a.obj"),
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  write_file(t.path("a.ply"),
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float "
             "y\nproperty float z\n"
             "element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 "
             "1 0\n0 0 1\n"
             "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  std::string ascii = "solid t\n";
  const double tri[4][3][3] = {{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}},
                               {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}},
                               {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                               {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (const auto& f : tri) {
    ascii += " facet normal 0 0 0\n  outer loop\n";
    for (const auto& v : f)
      ascii += "   vertex " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " +
               std::to_string(v[2]) + "\n";
    ascii += "  endloop\n endfacet\n";
  }
  ascii += "endsolid t\n";
  write_file(t.path("a.stl"), ascii);
  TriangleMesh m;
  for (const auto& v : {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)})
    m.vertices.push_back(v);
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  write_file(t.path("b.stl"), format_stl_binary(m));
  // Upper-case keywords, as some exporters write them (issue 63.12: read as a broken binary).
  std::string upper = ascii;
  for (const char* kw :
       {"solid", "facet", "normal", "outer", "loop", "vertex", "endloop", "endfacet", "endsolid"}) {
    std::string up = kw;
    for (char& ch : up) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    for (std::size_t at = upper.find(kw); at != std::string::npos; at = upper.find(kw, at)) {
      upper.replace(at, up.size(), up);
    }
  }
  REQUIRE(upper.rfind("SOLID t\n", 0) == 0);
  write_file(t.path("u.stl"), upper);
  for (const char* f : {"a.off", "a.obj", "a.ply", "a.stl", "b.stl", "u.stl"}) {
    INFO(f);
    const TriangleMesh r = read_mesh_file(t.path(f));
    CHECK(r.faces.size() == 4);
    CHECK(r.vertices.size() == 4);  // STL's 12 corner copies merged into 4 vertices
  }
}

TEST_CASE("mesh: an STL's corner copies merge exactly -- first seen first -- 0 and -0 alike",
          "[io][mesh]") {
  // Four triangles whose corners repeat: a copy equal in x, y and z (-0 equal to 0) is the
  // vertex first seen; a corner one unit of the last place away is a vertex of its own.
  const double apart = std::nextafter(1.0, 2.0);
  std::string ascii = "solid t\n";
  const double tri[4][3][3] = {{{5, 0, 0}, {0, 1, 0}, {1, 0, 0}},
                               {{-0.0, 1, -0.0}, {1, 0, 0}, {0, 0, 1}},
                               {{0, 0, 1}, {5, -0.0, 0}, {apart, 0, 0}},
                               {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  char number[64];
  for (const auto& f : tri) {
    ascii += " facet normal 0 0 0\n  outer loop\n";
    for (const auto& v : f) {
      ascii += "   vertex";
      for (double c : v) {
        std::snprintf(number, sizeof number, " %.17g", c);
        ascii += number;
      }
      ascii += "\n";
    }
    ascii += "  endloop\n endfacet\n";
  }
  ascii += "endsolid t\n";
  TempDir t;
  write_file(t.path("m.stl"), ascii);
  const TriangleMesh r = read_mesh_file(t.path("m.stl"));
  // First seen: (5,0,0) (0,1,0) (1,0,0) (0,0,1) (1+ulp,0,0).
  REQUIRE(r.vertices.size() == 5);
  CHECK(r.vertices[0] == Vec3d(5, 0, 0));
  CHECK(r.vertices[1] == Vec3d(0, 1, 0));
  CHECK(r.vertices[2] == Vec3d(1, 0, 0));
  CHECK(r.vertices[3] == Vec3d(0, 0, 1));
  CHECK(r.vertices[4] == Vec3d(apart, 0, 0));
  REQUIRE(r.faces.size() == 4);
  CHECK(r.faces[0] == std::array<int, 3>{0, 1, 2});
  CHECK(r.faces[1] == std::array<int, 3>{1, 2, 3});
  CHECK(r.faces[2] == std::array<int, 3>{3, 0, 4});
  CHECK(r.faces[3] == std::array<int, 3>{2, 1, 3});
}

TEST_CASE("mesh: the demo part reads with shared vertices", "[io][mesh]") {
  const TriangleMesh m = read_mesh_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl");
  CHECK(m.faces.size() > 10000);
  CHECK(m.vertices.size() < m.faces.size());
}

TEST_CASE("mesh: every bad mesh kind is an error naming the file", "[io][mesh][bad-input]") {
  TempDir t;
  write_file(t.path("empty.stl"), "");
  expect_mesh_error(t.path("empty.stl"), "empty");
  write_file(t.path("garbled.stl"), "this is not a mesh at all, just some words\n");
  expect_mesh_error(t.path("garbled.stl"), "part mesh");
  write_file(t.path("garbled.off"), "OFF\n4 4 0\n0 0 0\n1 zero 0\n");
  expect_mesh_error(t.path("garbled.off"), "part mesh");
  write_file(t.path("nan.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n");
  expect_mesh_error(t.path("nan.off"), "");
  write_file(t.path("flat.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n");
  expect_mesh_error(t.path("flat.off"), "degenerate");
  write_file(t.path("nofaces.off"), "OFF\n3 0 0\n0 0 0\n1 0 0\n2 0 0\n");
  expect_mesh_error(t.path("nofaces.off"), "");
  write_file(t.path("a.3ds"), "x");
  expect_mesh_error(t.path("a.3ds"), "must be .stl");
  expect_mesh_error(t.path("missing.stl"), "cannot open");
}

TEST_CASE(
    "mesh: a CAD export's zero-area slivers are dropped and counted, the part kept whole -- a "
    "mesh of slivers only is refused",
    "[io][mesh][cli][slow]") {
  TempDir t;
  // The demo part with a collinear and a coincident sliver added (36,608 faces + 2).
  const std::string demo = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  TriangleMesh m = read_mesh_file(demo + "sine.stl");
  const std::size_t faces = m.faces.size();
  const int a = m.faces[100][0], b = m.faces[100][1];
  m.vertices.push_back(
      0.5 * (m.vertices[static_cast<std::size_t>(a)] + m.vertices[static_cast<std::size_t>(b)]));
  const int mid = static_cast<int>(m.vertices.size()) - 1;
  m.faces.push_back({a, mid, b});
  m.faces.push_back({a, a, b});
  write_file(t.path("slivers.stl"), format_stl_binary(m));
  const TriangleMesh r = read_mesh_file(t.path("slivers.stl"));
  CHECK(r.faces.size() == faces);
  CHECK(r.dropped_degenerate_faces == 2);
  CHECK((r.first_degenerate_mm - m.vertices[static_cast<std::size_t>(a)]).norm() < 1e-4);
  // The run: the same program as with the clean part, and a warning saying what was dropped.
  const auto run = [&](const std::string& part, const std::string& out) {
    return run_taxopt("--in " + demo + "sine.cls --part " + part + " --method paper -q --gcode " +
                      t.path(out + ".nc") + " --report " + t.path(out + ".json"));
  };
  REQUIRE(run(t.path("slivers.stl"), "s").code == 0);
  REQUIRE(run(demo + "sine.stl", "c").code == 0);
  CHECK(read_file(t.path("s.nc")) == read_file(t.path("c.nc")));
  CHECK_THAT(read_file(t.path("s.json")),
             Catch::Contains("\"code\": \"mesh_slivers\"") &&
                 Catch::Contains("2 zero-area faces (slivers) dropped"));
  CHECK_THAT(read_file(t.path("c.json")), !Catch::Contains("mesh_slivers"));
}

TEST_CASE("cli: a bad part exits 2 naming the part file -- a wrong part names the CL line",
          "[cli][mesh][bad-input]") {
  TempDir t;
  write_file(t.path("flat.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n");
  const std::string cls = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls";
  auto r = run_taxopt("--in " + cls + " --part " + t.path("flat.off") + " --gcode " +
                      t.path("o.nc") + " --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("taxopt: error: " + t.path("flat.off") + ": "));
  CHECK_FALSE(file_exists(t.path("o.nc")));
  // The demo part, 50 mm away: no contact.
  write_file(t.path("far.off"), "OFF\n3 1 0\n0 0 -50\n100 0 -50\n0 100 -50\n3 0 1 2\n");
  r = run_taxopt("--in " + cls + " --part " + t.path("far.off") + " --gcode " + t.path("o.nc") +
                 " --method none");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("no CL point touches the part"));
  CHECK_FALSE(file_exists(t.path("o.nc")));
}

TEST_CASE("cli: with the part, the CSV has contact point, normal, tilt and yaw", "[cli][mesh]") {
  TempDir t;
  const std::string d = std::string(TAXOPT_SOURCE_DIR) + "/data/demo/";
  const auto r =
      run_taxopt("--in " + d + "sine.cls --part " + d + "sine.stl --points-csv " + t.path("p.csv") +
                 " --report " + t.path("r.json") + " --method none --gauge-length 15 -q" +
                 " --grid 6");  // free_cells on a coarse grid: minutes less under ASan
  REQUIRE(r.code == 0);
  const std::string csv = read_file(t.path("p.csv"));
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  int with_contact = 0, rows = 0;
  double tilt_sum = 0.0;
  while (std::getline(in, line)) {
    ++rows;
    std::vector<std::string> cols;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cols.push_back(cell);
    if (cols.size() > 16 && !cols[9].empty()) {
      ++with_contact;
      // tilt_deg: the demo's 5 deg against the designed surface's normal (the mesh's facets'
      // normals stray from the sine's by up to 3.5 deg, measured; the smooth one's by 0.3).
      CHECK(std::stod(cols[15]) == Approx(5.0).margin(0.5));
      tilt_sum += std::stod(cols[15]);
      CHECK(std::abs(std::stod(cols[16])) < 0.5);  // yaw_deg: 0
    }
  }
  CHECK(with_contact > 1900);
  CHECK(tilt_sum / with_contact == Approx(5.0).margin(0.05));
  CHECK(rows - with_contact < 200);  // approach and retract points only
}

TEST_CASE(
    "mesh: a broken text mesh names its line and what is wrong there -- a vertex past 1 km "
    "names its face",
    "[io][mesh][bad-input]") {
  TempDir t;
  struct Case {
    const char* name;
    std::string text;
    int line;
    const char* says;
  };
  const Case cases[] = {
      {"nan.stl",
       "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 nan\nvertex 0 1 0\n"
       "endloop\nendfacet\nendsolid x\n",
       5, "a vertex needs three finite numbers"},
      {"two.stl",
       "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"
       "endfacet\nendsolid x\n",
       6, "a facet of 2 vertices"},
      {"open.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", 4,
       "ends inside a solid"},
      {"corner.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 6,
       "face corner 7 names no vertex (0 to 2)"},
      {"short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n", 4, "ends after 2 of 4 vertices"},
      {"head.off", "OF\n3 1 0\n", 1, "the first line must be 'OFF'"},
      {"corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 4,
       "face corner 9 names no vertex (3 so far)"},
      {"record.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvx 1\nf 1 2 3\n", 4, "'vx' is no OBJ record"},
      {"vertex.obj", "v 0 0\nf 1 1 1\n", 1, "three finite numbers"},
      {"format.ply", "ply\nformat text 1.0\nend_header\n", 2, "is no PLY format"},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    write_file(t.path(c.name), c.text);
    try {
      read_mesh_file(t.path(c.name));
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK(e.line() == c.line);
      CHECK_THAT(e.message(), Catch::Contains(c.says));
    }
  }
  // A binary STL vertex at 1e38 is named with its face (before: a later face was called
  // degenerate, the areas overflowing).
  TriangleMesh m;
  m.vertices = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(1e38, 0, 0)};
  m.faces = {{0, 1, 2}, {1, 3, 2}};
  write_file(t.path("far.stl"), format_stl_binary(m));
  expect_mesh_error(t.path("far.stl"), "part mesh face 2 has a vertex beyond +-1e6");
  write_file(t.path("far.off"), "OFF\n3 1 0\n0 0 0\n2e6 0 0\n0 1 0\n3 0 1 2\n");
  expect_mesh_error(t.path("far.off"), "part mesh vertex 2 lies beyond +-1e6");
}
