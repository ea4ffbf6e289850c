#pragma once
/// @file The configuration space of tool axes at a contact point (paper section 3.1, fig. 10):
/// a grid over tilt a in [-90, 90) deg and yaw b in [-180, 180) deg in the local frame
/// (T, K, N) of the contact, axis V = Rot(N, b) Rot(K, a) N (eq. 11). A cell is free when the
/// local gouge check passes (eq. 19), its axis lies within the deviation cone around the
/// input axis, and the tool above the ball (tool_model.hpp) at that axis does not meet the part.
///
/// (a, b) and (-a, b + 180) are the same axis: the grid covers the hemisphere twice, as in
/// the paper; it is computed once for a >= 0 and mirrored.

#include <array>
#include <cstdint>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/cspace/collision.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt {

/// Options of the C-space grid.
struct CSpaceOptions {
  /// Cell size in degrees; 180 must be a whole multiple of it.
  double cell_deg = 2.0;
  /// Largest angle between a free axis and the input axis, deg.
  double max_deviation_deg = 30.0;
};

/// Bitset of free cells, tilt-major.
class TAXOPT_API CSpaceGrid {
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

/// Free tool axes at a contact point, exact at every cell centre, without FCL: an independent
/// second implementation of brute_force_free_axes, and the fast one (docs/benchmarks.md).
///
/// A spherical occlusion map (DESIGN.md section 7): one byte per cell of the window's rows,
/// open or blocked. A point at distance d from the ball centre, direction u, lies inside a body
/// (radius r, from `start` to `end` along the axis) exactly for the axes V with
/// start <= d V.u <= end and d sin(angle) <= r: a ring of cells around u, row by row in tilt a
/// yaw interval or two. Built once per part: a tree of bounding spheres over the faces. Per
/// contact point, two walks of the tree:
/// - coarse: one point of the part per subtree of <= 64 faces blocks its ring (for certain);
/// - fine: a subtree or face whose possible ring (its bounding sphere, radius rho, within
///   r + rho of the axis and reaching the slab) holds no open cell is skipped; a face that is
///   left blocks the ring of its centroid, and the exact triangle-versus-cylinder test decides
///   only the open cells of its possible ring (a thin band where faces are small).
/// Spans are rounded outward for possible rings and inward for certain ones. The result does
/// not depend on the order of the walk. free_axes may be called from several threads at once.
class TAXOPT_API CSpaceRasteriser : public PartCheck {
 public:
  explicit CSpaceRasteriser(const TriangleMesh& mesh);
  /// As CSpaceRasteriser(mesh), looking at `stop` as it builds its tree: a stop requested from
  /// another thread ends the build with Cancelled (or the stop's reason).
  CSpaceRasteriser(const TriangleMesh& mesh, const StopSource& stop);

  CSpaceGrid free_axes(const ToolModel& tool, const ContactPoint& contact, const Vec3d& ball_centre,
                       const Vec3d& input_axis, const CSpaceOptions& options = {}) const;

  /// Whether the tool's bodies at one axis (and the ball, with `with_ball`) meet the part: the
  /// question CollisionModel::collides answers with FCL, answered on this tree with the exact
  /// triangle-versus-cylinder test (and the triangle's closest point to the ball centre).
  bool collides(const ToolModel& tool, const Vec3d& ball_centre, const Vec3d& axis,
                bool with_ball = false) const override;

  /// Number of faces of the part.
  std::size_t faces() const { return tri_.size(); }

 private:
  struct Sphere {
    Vec3d centre = Vec3d::Zero();
    double radius = 0.0;
  };
  struct Node {
    Sphere sphere;
    /// Children (inner node, else -1) and the range [first, first + count) of its faces.
    int left = -1, right = -1, first = 0, count = 0;
  };
  /// A node's faces between two planes: lo <= normal . p <= hi for every corner p (normal:
  /// their area-weighted mean, turned to agree). collides drops a node whose sphere meets a
  /// body but whose slab no body reaches: the faces under a tool standing over them.
  struct Slab {
    Vec3d normal = Vec3d::UnitZ();
    double lo = 0.0, hi = 0.0;
  };
  /// The tree's build: each face's centroid (in the mesh's order), the face at each place of
  /// the tree's order, and room for one node's order.
  struct Build {
    const std::vector<Vec3d>& centroids;
    std::vector<int> perm, scratch;
  };
  int build(int first, int count, Build& b, const StopSource& stop);
  Slab slab_of(int first, int count, const Build& b) const;
  /// One free_axes call's walk of the tree (cspace.cpp).
  class Walk;
  std::vector<std::array<Vec3d, 3>> tri_;
  std::vector<Sphere> face_sphere_;
  std::vector<Node> nodes_;
  /// Per node (collides only; the occlusion map's walk needs the spheres alone).
  std::vector<Slab> slab_;
};

/// One-off convenience: builds a CSpaceRasteriser for `part` and asks it once. Build the
/// rasteriser yourself to ask for many points.
TAXOPT_API CSpaceGrid rasterise_free_axes(const Part& part, const ToolModel& tool,
                                          const ContactPoint& contact, const Vec3d& ball_centre,
                                          const Vec3d& input_axis,
                                          const CSpaceOptions& options = {});

/// The unit tool axis, workpiece coordinates, at the centre of cell (i, j) of a contact's
/// grid: V = N cos a + sin a (T cos b + K sin b) (eq. 11).
TAXOPT_API Vec3d cell_axis(const CSpaceGrid& grid, int i, int j, const ContactPoint& contact);

/// The free axes of a contact's grid, each once (the cells of tilt >= 0), workpiece
/// coordinates, tilt-major.
TAXOPT_API std::vector<Vec3d> free_axes_of(const CSpaceGrid& grid, const ContactPoint& contact);

/// The same as machine poses (A, C): for each free axis the inverse solution with A within
/// the machine's range (branch A >= 0 first); axes the machine cannot reach are left out.
TAXOPT_API std::vector<Posed> free_poses_of(const CSpaceGrid& grid, const ContactPoint& contact,
                                            const MachineKinematicsd& machine);

/// The same grid by brute force: one FCL collision query per cell (the reference).
TAXOPT_API CSpaceGrid brute_force_free_axes(const CollisionModel& model, const ToolModel& tool,
                                            const ContactPoint& contact, const Vec3d& ball_centre,
                                            const Vec3d& input_axis,
                                            const CSpaceOptions& options = {});

/// True when the solid cylinder of radius r about the axis from `origin` along unit `dir`,
/// between `start` and `end` along it, meets triangle (a, b, c). Exact up to rounding.
TAXOPT_API bool triangle_meets_cylinder(const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                        const Vec3d& origin, const Vec3d& dir, double r,
                                        double start, double end);

}  // namespace taxopt
