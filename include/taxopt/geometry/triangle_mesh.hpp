#pragma once
/// @file Indexed triangle mesh (part geometry), and tessellation of a parametric surface.

#include <array>
#include <cstddef>
#include <vector>

#include "taxopt/core/types.hpp"

namespace taxopt {

/// Triangles over shared vertices, millimetres, counter-clockwise seen from outside.
struct TriangleMesh {
  std::vector<Vec3d> vertices;
  std::vector<std::array<int, 3>> faces;
  /// Zero-area faces (slivers: collinear or coincident corners) the file held and the reader
  /// dropped -- they cover no surface --, and where the first lay.
  std::size_t dropped_degenerate_faces = 0;
  Vec3d first_degenerate_mm = Vec3d::Zero();
};

/// Tessellates a surface over its domain into a grid of (nu x nv) quads, two triangles each,
/// oriented along the surface normal (eq. 2).
template <class Surface>
TriangleMesh tessellate(const Surface& s, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i <= nu; ++i) {
    const double u = s.u_min() + (s.u_max() - s.u_min()) * i / nu;
    for (int j = 0; j <= nv; ++j) {
      const double v = s.v_min() + (s.v_max() - s.v_min()) * j / nv;
      m.vertices.push_back(s.jet(u, v).p);
    }
  }
  const auto id = [nv](int i, int j) { return i * (nv + 1) + j; };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      // (u, v) counter-clockwise is along S_u x S_v.
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

}  // namespace taxopt
