#pragma once
/// @file The configuration space of tool axes at a contact point (paper section 3.1, fig. 10):
/// a grid over tilt a in [-90, 90) deg and yaw b in [-180, 180) deg in the local frame
/// (T, K, N) of the contact, axis V = Rot(N, b) Rot(K, a) N (eq. 11). A cell is free when the
/// local gouge check passes (eq. 19), its axis lies within the deviation cone around the
/// input axis, and the tool above the ball (tool_model.hpp) at that axis does not meet the part.
///
/// (a, b) and (-a, b + 180) are the same axis: the grid covers the hemisphere twice, as in
/// the paper; it is computed once for a >= 0 and mirrored.

#include <cstdint>
#include <vector>

#include "taxopt/cspace/collision.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"

namespace taxopt {

/// Options of the C-space grid.
struct CSpaceOptions {
  /// Cell size in degrees; 180 must be a whole multiple of it.
  double cell_deg = 2.0;
  /// Largest angle between a free axis and the input axis, deg.
  double max_deviation_deg = 30.0;
};

/// Bitset of free cells, tilt-major.
class CSpaceGrid {
 public:
  CSpaceGrid() = default;
  /// @throws InputError when 180 / cell_deg is not a whole number or the cell is not in (0, 90].
  explicit CSpaceGrid(double cell_deg);

  int tilt_cells() const { return n_tilt_; }
  int yaw_cells() const { return n_yaw_; }
  double cell_deg() const { return cell_deg_; }
  /// Centre of a cell, radians.
  double tilt_rad(int i) const;
  double yaw_rad(int j) const;

  bool free(int i, int j) const;
  void set_free(int i, int j, bool free);
  /// Free cells (each axis counted twice, as the grid covers the hemisphere twice).
  std::size_t free_count() const;

 private:
  double cell_deg_ = 2.0;
  int n_tilt_ = 0, n_yaw_ = 0;
  std::vector<std::uint64_t> bits_;
};

/// Free tool axes at a contact point, exact at every cell centre, without FCL: the faces
/// within the tool's reach of the ball centre, each tested per body only against the cells
/// whose axis its bounding sphere can reach (radial cone and axial slab); the test itself is
/// exact (the face clipped to the body's slab, then its distance to the body's axis).
/// An independent second implementation of brute_force_free_axes (docs/benchmarks.md has
/// both timed: within a 30 deg window FCL's BVH is faster than this face-by-face culling).
CSpaceGrid rasterise_free_axes(const Part& part, const ToolModel& tool, const ContactPoint& contact,
                               const Vec3d& ball_centre, const Vec3d& input_axis,
                               const CSpaceOptions& options = {});

/// The same grid by brute force: one FCL collision query per cell (the reference).
CSpaceGrid brute_force_free_axes(const CollisionModel& model, const ToolModel& tool,
                                 const ContactPoint& contact, const Vec3d& ball_centre,
                                 const Vec3d& input_axis, const CSpaceOptions& options = {});

/// True when the solid cylinder of radius r about the axis from `origin` along unit `dir`,
/// between `start` and `end` along it, meets triangle (a, b, c). Exact up to rounding.
bool triangle_meets_cylinder(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& origin,
                             const Vec3d& dir, double r, double start, double end);

}  // namespace taxopt
