// Part meshes through CGAL's polygon-soup readers (compiled here so that users of the public
// headers never include CGAL).
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <sstream>

#include "taxopt/core/error.hpp"
#include "taxopt/io/mesh_file.hpp"

namespace taxopt {

TriangleMesh read_mesh_file(const std::string& path) {
  using K = CGAL::Simple_cartesian<double>;
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
  try {
    ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
  } catch (const std::exception&) {
    ok = false;
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
