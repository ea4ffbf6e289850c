// FCL is used only here: public headers stay free of it.
#include "taxopt/cspace/collision.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>

#include <new>
#include <utility>

#include "taxopt/core/stop.hpp"

namespace taxopt {
namespace {

/// FCL's split of a BVH node (its default: at the mean of the primitives' centres), looking
/// at the stop first: the model of a million triangles is built in one call (endModel).
class StoppableSplitter : public fcl::detail::BVSplitter<fcl::OBBd> {
 public:
  explicit StoppableSplitter(StopSource stop)
      : fcl::detail::BVSplitter<fcl::OBBd>(fcl::detail::SPLIT_METHOD_MEAN),
        stop_(std::move(stop)) {}
  void computeRule(const fcl::OBBd& bv, unsigned int* primitive_indices,
                   int num_primitives) override {
    stop_.throw_if_stop_requested();
    fcl::detail::BVSplitter<fcl::OBBd>::computeRule(bv, primitive_indices, num_primitives);
  }

 private:
  StopSource stop_;
};

}  // namespace

struct CollisionModel::Impl {
  // OBB: 2.2-2.4x faster than OBBRSS for collide-only queries (DESIGN.md section 7); never
  // AABB/KDOP, for which FCL copies the model on every shape query.
  std::shared_ptr<fcl::BVHModel<fcl::OBBd>> bvh;
};

CollisionModel::CollisionModel(const TriangleMesh& mesh) : CollisionModel(mesh, StopSource()) {}

CollisionModel::CollisionModel(const TriangleMesh& mesh, const StopSource& stop)
    : impl_(std::make_unique<Impl>()) {
  stop.throw_if_stop_requested();
  std::vector<fcl::Vector3d> vertices(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) {
    triangles.emplace_back(static_cast<std::size_t>(f[0]), static_cast<std::size_t>(f[1]),
                           static_cast<std::size_t>(f[2]));
  }
  stop.throw_if_stop_requested();
  impl_->bvh = std::make_shared<fcl::BVHModel<fcl::OBBd>>();
  impl_->bvh->bv_splitter = std::make_shared<StoppableSplitter>(stop);
  // FCL reports a failed allocation by a return code ("BVH Error! Out of memory") and leaves a
  // model that crashes the first query (tests/test_bad_input.cpp: a segfault under ulimit -v with a
  // 183 MB part): every step is checked, and a failure is the out-of-memory it is.
  const auto ok = [](int code) {
    if (code != fcl::BVH_OK) throw std::bad_alloc();
  };
  ok(impl_->bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size())));
  ok(impl_->bvh->addSubModel(vertices, triangles));
  ok(impl_->bvh->endModel());
  impl_->bvh->computeLocalAABB();
}

CollisionModel::~CollisionModel() = default;
CollisionModel::CollisionModel(CollisionModel&&) noexcept = default;
CollisionModel& CollisionModel::operator=(CollisionModel&&) noexcept = default;

bool CollisionModel::collides(const ToolModel& tool, const Vec3d& centre, const Vec3d& axis,
                              bool with_ball) const {
  const fcl::Transform3d part_tf = fcl::Transform3d::Identity();
  const fcl::CollisionRequestd request;  // one contact is enough
  const Eigen::Quaterniond rot = Eigen::Quaterniond::FromTwoVectors(Vec3d::UnitZ(), axis);
  for (const ToolBody& b : tool.bodies) {
    const fcl::Cylinderd cyl(b.radius_mm, b.end_mm - b.start_mm);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.linear() = rot.toRotationMatrix();
    tf.translation() = centre + 0.5 * (b.start_mm + b.end_mm) * axis;
    fcl::CollisionResultd result;
    fcl::collide(&cyl, tf, impl_->bvh.get(), part_tf, request, result);
    if (result.isCollision()) return true;
  }
  if (with_ball) {
    const fcl::Sphered ball(tool.ball_radius_mm);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = centre;
    fcl::CollisionResultd result;
    fcl::collide(&ball, tf, impl_->bvh.get(), part_tf, request, result);
    if (result.isCollision()) return true;
  }
  return false;
}

}  // namespace taxopt
