#pragma once
// The verification's checks of one operation as written (verify_checks.cpp): the machine's
// dynamic limits, the collisions of the points and of the moves between them, the clearances,
// the C-space rows. verify.cpp runs them per operation; verify_program.cpp checks the
// program's other blocks.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/stages.hpp"

namespace taxopt::pipeline {

/// A guaranteed lower bound of the least distance between the part and the tool's bodies that
/// do not cut (shank and holder, past the flutes; the flutes touch the part at a contact by
/// design) over the CL points with axes `axes`, and the point where it occurs; empty when the
/// tool has no such bodies. The bodies grown by d in radius and at both ends hold every point
/// within d of them, so where the grown bodies miss the part the clearance is at least d (and
/// at most d sqrt 2). d comes from bisecting FCL collision queries (exact distances cost 5 ms to
/// 0.3 s a query on flat parts): at 32 spread points first, then only at the points whose
/// bodies, grown by that bound, touch the part. Capped at 10 mm, 5 um steps; the same result
/// whatever the thread count.
std::optional<std::pair<double, std::size_t>> clearance_bound(const CollisionModel& model,
                                                              const ToolModel& tool,
                                                              const Operationd& op,
                                                              const std::vector<Vec3d>& axes,
                                                              detail::StageProgress* progress);

/// Checks operation `op_index`'s joints' velocity, acceleration and jerk at the written feeds
/// (`at`: its points' blocks among the program's `moves`, read back) against the machine's
/// limits (0: none; with a feed schedule the effective ones it was planned to), as the
/// controller moves: block times from the F words, each chain of feed moves from rest to rest.
/// Velocity and acceleration beyond a limit are problems, jerk a warning (the schedule does
/// not bound it).
void check_dynamic_limits(const Run& run, std::size_t op_index, const PostedOperation& po,
                          const std::vector<const GcodeMove*>& at,
                          const std::vector<GcodeMove>& moves, OperationResult& r, JobResult& res);

/// What hits at point i (axis `axis`): the first body of the judged `tool` past the flutes
/// that meets the part, how far its real body (`real_tool`) stays from it (or that it enters
/// it), and, for the shank, the flute length that would clear it when one does: the words a
/// refusal gives (tests/test_paper_method.cpp).
std::string what_hits(const CollisionModel& model, const ToolModel& tool,
                      const ToolModel& real_tool, const Operationd& op, std::size_t i,
                      const Vec3d& axis, bool in_air, const JobOptions& options);

/// The collisions of an operation's points and moves as written (FCL, the reference), told
/// apart by body, and the clearance of the bodies that do not cut.
void check_collisions(const Run& run, const OperationContext& o, const PostedOperation& po,
                      const Written& w, const std::vector<Vec3d>& xyz_w,
                      const std::vector<double>& a_w, const std::vector<double>& c_w,
                      detail::StageProgress& checking, OperationResult& r, JobResult& res);

/// An operation whose tool is no ball end (flat, bull nose) with a part: no contact model, so
/// its flutes are not judged, but its shank and holder, which never cut, are checked at every
/// point and along every move as written, with their clearances (tests/test_bad_input.cpp: the demo
/// with a corner radius of 1 mm was posted with 330 shank collisions at exit 0).
void check_shank_and_holder(const Run& run, const OperationContext& o, const PostedOperation& po,
                            const Written& w, const std::vector<Vec3d>& xyz_w,
                            const std::vector<double>& a_w, const std::vector<double>& c_w,
                            OperationResult& r, JobResult& res);

/// The free cells of every contact's C-space (--count-free-cells) and the maps of the most
/// constrained contact and the most turned one (--cspace-maps).
void cspace_rows(const Run& run, const OperationContext& o, detail::StageProgress& checking,
                 OperationResult& r);

}  // namespace taxopt::pipeline
