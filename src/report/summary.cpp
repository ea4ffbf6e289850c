// One operation's summary for the CLI's table and the page (taxopt/job.hpp, SummaryRow).
#include "taxopt/job.hpp"

namespace taxopt {

std::vector<SummaryRow> summary_rows(const JobResult& result) {
  std::vector<SummaryRow> rows;
  rows.reserve(result.operations.size());
  for (const OperationResult& r : result.operations) {
    SummaryRow row;
    row.operation = r.name;
    row.points = r.points;
    row.peak_omega_deg_s = {r.before.max_omega_deg_s, r.after.max_omega_deg_s};
    row.peak_accel_deg_s2 = {r.before.max_accel_deg_s2, r.after.max_accel_deg_s2};
    row.rms_accel_deg_s2 = {r.before.rms_accel_deg_s2, r.after.rms_accel_deg_s2};
    row.c_jumps = {r.before.c_jumps, r.after.c_jumps};
    if (r.colliding_before && r.colliding_after) {
      row.colliding_points = BeforeAfter<long>{*r.colliding_before, *r.colliding_after};
    }
    row.colliding_moves = r.verification.colliding_moves;
    if (r.kept_input_points) row.input_axes_kept = r.kept_input_points->total();
    row.max_axis_change_deg = r.max_axis_change_deg;
    row.feed_time_s = {r.feed_before.feed_time_s, r.feed_after.feed_time_s};
    row.cycle_time_s = {r.feed_before.cycle_time_s, r.feed_after.cycle_time_s};
    row.compute_s =
        r.time_contacts_s + r.time_cspace_s + r.time_optimise_s + r.time_post_s + r.time_verify_s;
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace taxopt
