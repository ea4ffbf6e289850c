#pragma once
/// @file The exact tests of one triangle against the tool's bodies, internal to the C-space
/// rasteriser (triangle_meets_cylinder in taxopt/cspace/cspace.hpp is their public face).

#include <array>

#include "taxopt/core/types.hpp"

namespace taxopt::detail {

/// triangle_meets_cylinder with the vertices given relative to the axis origin and the axis
/// in an orthonormal frame (e1, e2, dir): the cylinder of radius r from `start` to `end` along
/// dir.
bool meets_in_frame(const std::array<Vec3d, 3>& rel, const Vec3d& dir, const Vec3d& e1,
                    const Vec3d& e2, double r, double start, double end);

/// The squared distance from p to the triangle abc.
double squared_distance_to_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace taxopt::detail
