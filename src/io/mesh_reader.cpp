// Part meshes through CGAL's polygon-soup readers (compiled here so that users of the public
// headers never include CGAL).
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "taxopt/io/mesh_file.hpp"

namespace taxopt {
namespace {

using K = CGAL::Simple_cartesian<double>;

/// Reads a binary STL whose size fits its header's triangle count; false when the file is no
/// binary STL (then it is ASCII, or broken: the caller says which). A binary STL is told by its
/// size, not by the word "solid" (many exporters begin binary headers with it).
bool read_binary_stl(const std::string& path, std::vector<K::Point_3>& points,
                     std::vector<std::vector<std::size_t>>& polygons) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open part mesh");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t first = 0;
  while (first < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[first]))) ++first;
  const bool says_solid = bytes.compare(first, 5, "solid") == 0;
  if (bytes.size() < 84) {
    if (says_solid) return false;
    throw InputError(path, 0,
                     "part mesh is no STL file: " + std::to_string(bytes.size()) +
                         " bytes, shorter than a binary STL header (84) and not ASCII ('solid')");
  }
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);  // little-endian on every machine taxopt runs on
  const std::uint64_t expect = 84 + 50ull * count;
  if (expect != bytes.size()) {
    if (says_solid) return false;  // ASCII
    throw InputError(path, 0,
                     "part mesh: its binary STL header says " + std::to_string(count) +
                         " triangles, that is " + std::to_string(expect) +
                         " bytes, but the file has " + std::to_string(bytes.size()) + " bytes");
  }
  points.clear();
  polygons.clear();
  points.reserve(3ull * count);
  polygons.reserve(count);
  for (std::uint32_t f = 0; f < count; ++f) {
    const char* rec = bytes.data() + 84 + 50ull * f;
    std::vector<std::size_t> poly;
    for (int v = 0; v < 3; ++v) {
      float xyz[3];
      std::memcpy(xyz, rec + 12 + 12 * v, 12);
      if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
        throw InputError(path, 0,
                         "part mesh face " + std::to_string(f + 1) +
                             " has a vertex that is not "
                             "finite (NaN or infinity)");
      }
      poly.push_back(points.size());
      points.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
    polygons.push_back(std::move(poly));
  }
  return true;
}

}  // namespace

TriangleMesh read_mesh_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "cannot open part mesh");
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".stl" && ext != ".obj" && ext != ".off" && ext != ".ply") {
    throw InputError(path, 0, "part mesh must be .stl, .obj, .off or .ply, got '" + ext + "'");
  }
  if (fs::file_size(path, ec) == 0) throw InputError(path, 0, "part mesh is empty");
  std::vector<K::Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  if (ext == ".stl" && read_binary_stl(path, points, polygons)) {
    ok = true;
  } else {
    try {
      ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok)
    throw InputError(path, 0, "cannot read part mesh: not a valid " + ext.substr(1) + " file");
  if (polygons.empty() || points.empty()) throw InputError(path, 0, "part mesh has no faces");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      throw InputError(path, 0, "part mesh vertex " + std::to_string(i + 1) + " is not finite");
    }
  }
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    if (polygons[f].size() < 3) {
      throw InputError(path, 0,
                       "part mesh face " + std::to_string(f + 1) + " has fewer than 3 vertices");
    }
    for (std::size_t v : polygons[f]) {
      if (v >= points.size()) {
        throw InputError(path, 0,
                         "part mesh face " + std::to_string(f + 1) + " names a missing vertex");
      }
    }
  }
  // An STL is a soup: one copy of a vertex per triangle. Merge exact duplicates.
  CGAL::Polygon_mesh_processing::merge_duplicate_points_in_polygon_soup(points, polygons);

  TriangleMesh mesh;
  mesh.vertices.reserve(points.size());
  Eigen::AlignedBox3d box;
  for (const auto& p : points) {
    mesh.vertices.emplace_back(p.x(), p.y(), p.z());
    box.extend(mesh.vertices.back());
  }
  const double diag = box.diagonal().norm();
  const double min_area = 1e-14 * std::max(1.0, diag * diag);
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const auto& poly = polygons[f];
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) {  // fan: polygons become triangles
      const std::array<int, 3> t = {static_cast<int>(poly[0]), static_cast<int>(poly[k]),
                                    static_cast<int>(poly[k + 1])};
      const Vec3d& a = mesh.vertices[static_cast<std::size_t>(t[0])];
      const Vec3d& b = mesh.vertices[static_cast<std::size_t>(t[1])];
      const Vec3d& c = mesh.vertices[static_cast<std::size_t>(t[2])];
      if (0.5 * (b - a).cross(c - a).norm() <= min_area) {
        std::ostringstream os;
        os << "part mesh face " << f + 1 << " is degenerate (zero area) at (" << a.x() << ", "
           << a.y() << ", " << a.z() << ")";
        throw InputError(path, 0, os.str());
      }
      mesh.faces.push_back(t);
    }
  }
  return mesh;
}

}  // namespace taxopt
