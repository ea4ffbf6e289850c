#pragma once
/// @file Part meshes on disk: STL (binary and ASCII), OBJ, OFF, PLY.

#include <string>

#include "taxopt/core/export.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"

namespace taxopt {

/// Reads a part mesh (STL binary or ASCII, OBJ, OFF, PLY, by the file's extension) with CGAL.
/// Polygons are split into triangles, duplicated vertices merged (a polygon soup becomes an
/// indexed mesh). Zero-area faces (CAD exports' slivers) cover no surface: dropped and counted
/// (TriangleMesh::dropped_degenerate_faces). @throws InputError naming the file: unreadable or
/// garbled, empty, non-finite coordinates, no face of any area.
TAXOPT_API TriangleMesh read_mesh_file(const std::string& path);

/// Binary STL of a mesh (normals from the vertex order), as bytes.
TAXOPT_API std::string format_stl_binary(const TriangleMesh& mesh,
                                         const std::string& header = "taxopt");

}  // namespace taxopt
