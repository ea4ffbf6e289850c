#pragma once
/// @file Tool-versus-part collision checks with FCL: the part as one BVH (built once, shared
/// read-only by every thread), the tool bodies as FCL cylinders placed per query.
///
/// FCL reports surface contact only: a body entirely inside a closed mesh counts as free
/// (FCL issue #492). The bodies start at the ball centre, which contact recovery has shown to
/// be outside the part at distance R, so a body cannot be wholly inside without crossing the
/// surface; for points in the air the ball is checked as well.

#include <memory>

#include "taxopt/core/export.hpp"
#include "taxopt/core/stop.hpp"
#include "taxopt/cspace/tool_model.hpp"
#include "taxopt/geometry/triangle_mesh.hpp"

namespace taxopt {

/// Whether the tool at one pose meets the part. Two implementations: CollisionModel (FCL,
/// the reference every output is verified with) and CSpaceRasteriser (cspace.hpp: the
/// occlusion map's tree and exact triangle tests, 5-25x faster, what the optimisers ask).
class TAXOPT_API PartCheck {
 public:
  virtual ~PartCheck() = default;
  /// True when any body of `tool` placed with ball centre `centre_mm` and unit axis `axis`
  /// intersects the part; with `with_ball`, the ball counts too. Thread-safe.
  virtual bool collides(const ToolModel& tool, const Vec3d& centre_mm, const Vec3d& axis,
                        bool with_ball) const = 0;
};

/// The part for FCL (BVH of oriented bounding boxes).
class TAXOPT_API CollisionModel : public PartCheck {
 public:
  explicit CollisionModel(const TriangleMesh& mesh);
  /// As CollisionModel(mesh), looking at `stop` as FCL builds its tree (at every node): a stop
  /// requested from another thread ends the build with Cancelled (or the stop's reason).
  CollisionModel(const TriangleMesh& mesh, const StopSource& stop);
  ~CollisionModel();
  CollisionModel(CollisionModel&&) noexcept;
  CollisionModel& operator=(CollisionModel&&) noexcept;
  CollisionModel(const CollisionModel&) = delete;
  CollisionModel& operator=(const CollisionModel&) = delete;

  bool collides(const ToolModel& tool, const Vec3d& centre_mm, const Vec3d& axis,
                bool with_ball = false) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace taxopt
