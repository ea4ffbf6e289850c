#pragma once
/// @file Part meshes on disk: STL (binary and ASCII), OBJ, OFF, PLY.

#include <string>

#include "taxopt/geometry/triangle_mesh.hpp"

namespace taxopt {

/// Binary STL of a mesh (normals from the vertex order), as bytes.
std::string format_stl_binary(const TriangleMesh& mesh, const std::string& header = "taxopt");

}  // namespace taxopt
