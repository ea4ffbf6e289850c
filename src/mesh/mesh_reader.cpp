// Part meshes through CGAL's polygon-soup readers (compiled here so that users of the public
// headers never include CGAL).
#include <CGAL/IO/polygon_soup_io.h>
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

/// Why a text mesh CGAL could not read is broken: the first line that breaks its format, by a
/// plain scan of the format's records (OBJ v/f, OFF counts, vertices and faces, ASCII STL's
/// solid/facet/loop/vertex nesting, PLY's header); empty when the scan finds nothing.
struct Diagnosis {
  int line = 0;
  std::string why;
};

bool finite_numbers(std::istringstream& in, int count, double* out = nullptr) {
  for (int k = 0; k < count; ++k) {
    std::string tok;
    if (!(in >> tok)) return false;
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(v)) return false;
    if (out) out[k] = v;
  }
  return true;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// OBJ: vertices, faces whose corners name them, the records OBJ knows.
Diagnosis diagnose_obj(std::istream& in) {
  std::string line;
  int n = 0;
  const auto fail = [&](const std::string& why) { return Diagnosis{n, why}; };
  long vertices = 0;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream ls(line);
    std::string kind;
    if (!(ls >> kind) || kind[0] == '#') continue;
    if (kind == "v") {
      if (!finite_numbers(ls, 3)) return fail("a vertex 'v' needs three finite numbers");
      ++vertices;
    } else if (kind == "f") {
      int corners = 0;
      for (std::string tok; ls >> tok; ++corners) {
        char* end = nullptr;
        const long i = std::strtol(tok.c_str(), &end, 10);
        if (end == tok.c_str() || (*end != '\0' && *end != '/')) {
          return fail("face corner '" + tok.substr(0, 40) + "' is no vertex index");
        }
        if (i == 0 || i > vertices || -i > vertices) {
          return fail("face corner " + std::to_string(i) + " names no vertex (" +
                      std::to_string(vertices) + " so far)");
        }
      }
      if (corners < 3) return fail("a face 'f' needs at least three corners");
    } else if (kind != "vt" && kind != "vn" && kind != "vp" && kind != "g" && kind != "o" &&
               kind != "s" && kind != "usemtl" && kind != "mtllib" && kind != "l" && kind != "p") {
      return fail("'" + kind.substr(0, 40) + "' is no OBJ record");
    }
  }
  return {};
}

/// OFF: the header, the counts, the vertices, the faces.
Diagnosis diagnose_off(std::istream& in) {
  std::string line;
  int n = 0;
  const auto fail = [&](const std::string& why) { return Diagnosis{n, why}; };
  // Header, counts, vertices, faces; '#' comments and blank lines skipped.
  const auto next = [&](std::istringstream& ls) {
    while (std::getline(in, line)) {
      ++n;
      const std::size_t hash = line.find('#');
      if (hash != std::string::npos) line.erase(hash);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      ls = std::istringstream(line);
      return true;
    }
    return false;
  };
  std::istringstream ls;
  if (!next(ls)) return fail("empty");
  std::string head;
  ls >> head;
  if (head.size() < 3 || head.compare(head.size() - 3, 3, "OFF") != 0) {
    return fail("the first line must be 'OFF', got '" + head.substr(0, 40) + "'");
  }
  long nv = -1, nf = -1, ne = 0;
  if (!(ls >> nv)) {
    if (!next(ls)) return fail("no vertex and face counts");
    ls >> nv;
  }
  if (!(ls >> nf >> ne) || nv < 0 || nf < 0) {
    return fail("the counts must be 'vertices faces edges', whole numbers");
  }
  for (long v = 0; v < nv; ++v) {
    if (!next(ls))
      return fail("the file ends after " + std::to_string(v) + " of " + std::to_string(nv) +
                  " vertices");
    if (!finite_numbers(ls, 3)) return fail("a vertex needs three finite numbers");
  }
  for (long f = 0; f < nf; ++f) {
    if (!next(ls))
      return fail("the file ends after " + std::to_string(f) + " of " + std::to_string(nf) +
                  " faces");
    long k = 0;
    if (!(ls >> k) || k < 3) return fail("a face starts with its corner count, at least 3");
    for (long c = 0; c < k; ++c) {
      long i = -1;
      if (!(ls >> i)) return fail("a face lists fewer corners than its count");
      if (i < 0 || i >= nv) {
        return fail("face corner " + std::to_string(i) + " names no vertex (0 to " +
                    std::to_string(nv - 1) + ")");
      }
    }
  }
  return {};
}

/// ASCII STL: solid { facet normal / outer loop / three vertices / endloop / endfacet } endsolid,
/// its keywords in any case (some exporters write SOLID, FACET NORMAL, VERTEX); with `points`
/// and `polygons`, its triangles read into them (the ASCII STL reader).
Diagnosis diagnose_stl(std::istream& in, std::vector<K::Point_3>* points = nullptr,
                       std::vector<std::vector<std::size_t>>* polygons = nullptr) {
  std::string line;
  int n = 0;
  const auto fail = [&](const std::string& why) { return Diagnosis{n, why}; };
  // solid { facet normal n n n / outer loop / vertex x3 / endloop / endfacet } endsolid
  int state = 0, vertices = 0;  // 0 outside solid, 1 in solid, 2 in facet, 3 in loop
  while (std::getline(in, line)) {
    ++n;
    std::istringstream ls(line);
    std::string kw;
    if (!(ls >> kw)) continue;
    kw = lower(kw);
    if (kw == "solid" && state == 0) {
      state = 1;
    } else if (kw == "facet" && state == 1) {
      std::string normal;
      if (!(ls >> normal) || lower(normal) != "normal" || !finite_numbers(ls, 3)) {
        return fail("'facet normal' needs three finite numbers");
      }
      state = 2;
    } else if (kw == "outer" && state == 2) {
      state = 3;
      vertices = 0;
    } else if (kw == "vertex" && state == 3) {
      double xyz[3];
      if (!finite_numbers(ls, 3, xyz)) return fail("a vertex needs three finite numbers");
      if (points) points->emplace_back(xyz[0], xyz[1], xyz[2]);
      ++vertices;
    } else if (kw == "endloop" && state == 3) {
      if (vertices != 3) return fail("a facet of " + std::to_string(vertices) + " vertices");
      if (polygons) {
        const std::size_t last = points->size();
        polygons->push_back({last - 3, last - 2, last - 1});
      }
      state = 2;
    } else if (kw == "endfacet" && state == 2) {
      state = 1;
    } else if (kw == "endsolid" && state == 1) {
      state = 0;
    } else {
      return fail("'" + kw.substr(0, 40) + "' where " +
                  (state == 0   ? "'solid'"
                   : state == 1 ? "'facet' or 'endsolid'"
                   : state == 2 ? "'outer loop' or 'endfacet'"
                                : "'vertex' or 'endloop'") +
                  " belongs");
    }
  }
  if (state != 0) return fail("the file ends inside a solid (no 'endsolid')");
  return {};
}

/// PLY: the header, up to its end (the body is CGAL's to read).
Diagnosis diagnose_ply(std::istream& in) {
  std::string line;
  int n = 0;
  const auto fail = [&](const std::string& why) { return Diagnosis{n, why}; };
  if (!std::getline(in, line) || (++n, line.rfind("ply", 0) != 0)) {
    return fail("the first line must be 'ply'");
  }
  bool format = false;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "format") {
      std::string f;
      ls >> f;
      if (f != "ascii" && f != "binary_little_endian" && f != "binary_big_endian") {
        return fail("format '" + f.substr(0, 40) + "' is no PLY format");
      }
      format = true;
    } else if (kw == "end_header") {
      if (!format) return fail("a header without its 'format' line");
      return {};
    } else if (kw != "element" && kw != "property" && kw != "comment" && kw != "obj_info" &&
               !kw.empty()) {
      return fail("'" + kw.substr(0, 40) + "' is no PLY header line");
    }
  }
  return fail("the header has no 'end_header'");
}

Diagnosis diagnose_text_mesh(const std::string& path, const std::string& ext) {
  std::ifstream in(path, std::ios::binary);
  if (ext == ".obj") return diagnose_obj(in);
  if (ext == ".off") return diagnose_off(in);
  if (ext == ".stl") return diagnose_stl(in);
  if (ext == ".ply") return diagnose_ply(in);
  return {};
}

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
  const bool says_solid = lower(bytes.substr(first, 5)) == "solid";
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
      if (std::max({std::abs(xyz[0]), std::abs(xyz[1]), std::abs(xyz[2])}) > kMaxCoordinateMm) {
        throw InputError(path, 0,
                         "part mesh face " + std::to_string(f + 1) + " has a vertex beyond " +
                             "+-1e6 (1 km in mm): not a part on a machine");
      }
      poly.push_back(points.size());
      points.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
    polygons.push_back(std::move(poly));
  }
  return true;
}

}  // namespace

namespace {

/// Every vertex finite and within +-1e6 mm, every face of three or more vertices it has.
void check_soup(const std::string& path, const std::vector<K::Point_3>& points,
                const std::vector<std::vector<std::size_t>>& polygons) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      throw InputError(path, 0, "part mesh vertex " + std::to_string(i + 1) + " is not finite");
    }
    if (std::max({std::abs(p.x()), std::abs(p.y()), std::abs(p.z())}) > kMaxCoordinateMm) {
      throw InputError(path, 0,
                       "part mesh vertex " + std::to_string(i + 1) +
                           " lies beyond +-1e6 (1 km in mm): not a part on a machine");
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
}

/// CGAL's merge_duplicate_points_in_polygon_soup, by hashing instead of its std::map: the
/// points equal in x, y and z (0 and -0 alike) become the first of them, numbered in the order
/// they first appear, and the polygons name those (the same points and polygons; the read of
/// 490k faces 1.0 s -> 0.55 s). The points are finite (check_soup).
void merge_duplicate_points(std::vector<K::Point_3>& points,
                            std::vector<std::vector<std::size_t>>& polygons) {
  const std::size_t n = points.size();
  std::size_t size = 16;
  while (size < 2 * n) size *= 2;
  constexpr std::size_t kEmpty = static_cast<std::size_t>(-1);
  std::vector<std::size_t> table(size, kEmpty);  // a slot: the unique point's number
  const auto key = [](double v) {
    std::uint64_t bits = 0;
    v = v == 0.0 ? 0.0 : v;  // -0 hashes as 0
    std::memcpy(&bits, &v, sizeof bits);
    return bits;
  };
  std::vector<K::Point_3> unique;
  unique.reserve(n);
  std::vector<std::size_t> id(n);
  for (std::size_t i = 0; i < n; ++i) {
    const K::Point_3& p = points[i];
    std::uint64_t h = key(p.x()) * 0x9E3779B97F4A7C15ull;
    h = (h ^ key(p.y())) * 0xC2B2AE3D27D4EB4Full;
    h = (h ^ key(p.z())) * 0x165667B19E3779F9ull;
    std::size_t slot = static_cast<std::size_t>(h ^ (h >> 29)) & (size - 1);
    for (;; slot = (slot + 1) & (size - 1)) {
      if (table[slot] == kEmpty) {
        table[slot] = unique.size();
        unique.push_back(p);
        break;
      }
      const K::Point_3& q = unique[table[slot]];
      if (q.x() == p.x() && q.y() == p.y() && q.z() == p.z()) break;
    }
    id[i] = table[slot];
  }
  if (unique.size() == n) return;
  for (std::vector<std::size_t>& polygon : polygons) {
    for (std::size_t& v : polygon) v = id[v];
  }
  points = std::move(unique);
}

/// The merged soup as triangles (polygons fanned), slivers of no area dropped and counted.
TriangleMesh triangles_of(const std::vector<K::Point_3>& points,
                          const std::vector<std::vector<std::size_t>>& polygons) {
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
        // A sliver covers no surface: the faces around it hold the part's shape.
        if (mesh.dropped_degenerate_faces++ == 0) mesh.first_degenerate_mm = a;
        continue;
      }
      mesh.faces.push_back(t);
    }
  }
  return mesh;
}

}  // namespace

TriangleMesh read_mesh_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "cannot open part mesh");
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext != ".stl" && ext != ".obj" && ext != ".off" && ext != ".ply") {
    throw InputError(path, 0, "part mesh must be .stl, .obj, .off or .ply, got '" + ext + "'");
  }
  if (fs::file_size(path, ec) == 0) throw InputError(path, 0, "part mesh is empty");
  std::vector<K::Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  if (ext == ".stl" && read_binary_stl(path, points, polygons)) {
    ok = true;
  } else if (ext == ".stl") {
    // ASCII: its keywords in any case (CGAL's reader takes lower case only: an upper-case
    // export was refused as a broken binary STL, issue 63.12).
    std::ifstream text(path);
    ok = diagnose_stl(text, &points, &polygons).why.empty();
    if (!ok) points.clear(), polygons.clear();
  } else {
    try {
      ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok) {
    const Diagnosis d = diagnose_text_mesh(path, ext);
    throw InputError(path, d.line,
                     "cannot read part mesh: not a valid " + ext.substr(1) + " file" +
                         (d.why.empty() ? std::string() : ": " + d.why));
  }
  if (polygons.empty() || points.empty()) {
    const Diagnosis d = diagnose_text_mesh(path, ext);
    throw InputError(path, d.line,
                     "part mesh has no faces" + (d.why.empty() ? std::string() : ": " + d.why));
  }
  check_soup(path, points, polygons);
  // An STL is a soup: one copy of a vertex per triangle. Merge exact duplicates.
  merge_duplicate_points(points, polygons);
  TriangleMesh mesh = triangles_of(points, polygons);
  if (mesh.faces.empty()) {
    throw InputError(path, 0,
                     "part mesh: every one of its " +
                         std::to_string(mesh.dropped_degenerate_faces) +
                         " faces is degenerate (zero area): no surface");
  }
  return mesh;
}

}  // namespace taxopt
