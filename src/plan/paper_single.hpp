#pragma once
/// @file The paper method's plan of a pass and, in the same run, its plan without the resettle
/// rounds (PaperOptions::resettle_rounds): the pipeline keeps whichever turns the axes less
/// against their limits, and planning the pass twice cost a fifth of a held least tilt's run.

#include <optional>

#include "taxopt/plan/paper_optimiser.hpp"

namespace taxopt::detail {

/// plan_pass_paper; `single` receives what it returns with no resettle rounds where a round
/// ran (a repair added keys), else nothing.
PassPlan plan_pass_paper(const PassProblem& problem, const AxisTest& is_free,
                         const PaperOptions& options, std::optional<PassPlan>& single);

}  // namespace taxopt::detail
