#include <cstdint>
#include <cstring>

#include "taxopt/io/mesh_file.hpp"

namespace taxopt {
namespace {

void put_f32(std::string& out, double v) {
  const float f = static_cast<float>(v);
  char b[4];
  std::memcpy(b, &f, 4);  // STL is little-endian, as is every machine taxopt runs on
  out.append(b, 4);
}

}  // namespace

std::string format_stl_binary(const TriangleMesh& mesh, const std::string& header) {
  std::string out(80, ' ');
  out.replace(0, std::min<std::size_t>(header.size(), 80), header.substr(0, 80));
  const auto n = static_cast<std::uint32_t>(mesh.faces.size());
  char b[4];
  std::memcpy(b, &n, 4);
  out.append(b, 4);
  out.reserve(out.size() + 50 * mesh.faces.size());
  for (const auto& f : mesh.faces) {
    const Vec3d& a = mesh.vertices[static_cast<std::size_t>(f[0])];
    const Vec3d& bb = mesh.vertices[static_cast<std::size_t>(f[1])];
    const Vec3d& c = mesh.vertices[static_cast<std::size_t>(f[2])];
    Vec3d nrm = (bb - a).cross(c - a);
    if (nrm.norm() > 0.0) nrm.normalize();
    for (const Vec3d& v : {nrm, a, bb, c}) {
      put_f32(out, v.x());
      put_f32(out, v.y());
      put_f32(out, v.z());
    }
    out.append(2, '\0');
  }
  return out;
}

}  // namespace taxopt
