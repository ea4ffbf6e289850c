#pragma once
/// @file Private helper of the compiled library (not installed): contact recovery that reports
/// each point to a stage's progress (a job's bar moves per point, not per operation) and stops
/// with the job.

#include <vector>

#include "taxopt/geometry/contact.hpp"
#include "util/progress.hpp"

namespace taxopt::detail {

/// recover_contacts, advancing `progress` (when given) once a point; throws as
/// StageProgress::advance does when the job is to stop.
std::vector<ContactPoint> recover_contacts(const Part& part, const Operationd& op,
                                           double ball_radius_mm, const ContactOptions& options,
                                           StageProgress* progress);

}  // namespace taxopt::detail
