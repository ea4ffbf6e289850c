// One operation's summary for the CLI's table and the page (taxopt/job.hpp, SummaryRow).
#include "taxopt/job.hpp"

namespace taxopt {

std::optional<AxisShare> worst_axis_share(const RotarySummary& before, const RotarySummary& after,
                                          const Machine& machine) {
  std::optional<AxisShare> worst;
  const auto consider = [&](Joint joint, const AxisPeaks& b, const AxisPeaks& a) {
    const JointLimit& limit = machine.limits[static_cast<std::size_t>(joint)];
    const char letter = joint_name(joint, machine.rotary.tilt_letter()).front();
    const auto share = [&](const char* rate, double limit_value, double peak_before,
                           double peak_after) {
      if (!(limit_value > 0.0)) return;
      AxisShare s{letter, rate, limit_value, peak_before / limit_value, peak_after / limit_value};
      if (!worst || std::max(s.before, s.after) > std::max(worst->before, worst->after)) {
        worst = s;
      }
    };
    share("omega", limit.max_velocity_per_s, b.max_omega_deg_s, a.max_omega_deg_s);
    share("accel", limit.max_accel_per_s2, b.max_accel_deg_s2, a.max_accel_deg_s2);
  };
  consider(Joint::Tilt, before.tilt, after.tilt);
  consider(Joint::C, before.c, after.c);
  return worst;
}

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
    row.peak_omega_tilt_deg_s = {r.before.tilt.max_omega_deg_s, r.after.tilt.max_omega_deg_s};
    row.peak_omega_c_deg_s = {r.before.c.max_omega_deg_s, r.after.c.max_omega_deg_s};
    row.peak_accel_tilt_deg_s2 = {r.before.tilt.max_accel_deg_s2, r.after.tilt.max_accel_deg_s2};
    row.peak_accel_c_deg_s2 = {r.before.c.max_accel_deg_s2, r.after.c.max_accel_deg_s2};
    row.tilt_letter = result.tilt_letter;
    row.worst_axis = r.worst_axis;
    if (r.cutting) {
      row.least_cutting_diameter_mm = BeforeAfter<double>{r.cutting->least_diameter_before_mm,
                                                          r.cutting->least_diameter_after_mm};
    }
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
