// What the command line prints: progress, the job's messages and the summary table.
#include <cstdio>
#include <iostream>

#include "cli.hpp"

namespace taxopt::cli {
namespace {

/// "before -> after (-x %)".
std::string before_after(double before, double after, const char* format) {
  char b[32], a[32], pct[32] = "";
  std::snprintf(b, sizeof b, format, before);
  std::snprintf(a, sizeof a, format, after);
  if (before > 0.0) std::snprintf(pct, sizeof pct, " (%+.0f %%)", 100.0 * (after / before - 1.0));
  return std::string(b) + " -> " + a + pct;
}

}  // namespace

int error(const std::string& what, int code) {
  std::cerr << "taxopt: error: " << what << "\n";
  return code;
}

/// The headline of a row: the axis nearest its machine limit, as shares of the limit, where
/// the machine file gives limits; else the paper's combined peak a.
static std::string worst_axis_cell(const SummaryRow& r) {
  if (!r.worst_axis) {
    return "(combined a) " +
           before_after(r.peak_accel_deg_s2.before, r.peak_accel_deg_s2.after, "%.1f");
  }
  const AxisShare& w = *r.worst_axis;
  return std::string(1, w.axis) + " " + (w.rate == "omega" ? "omega " : "a ") +
         before_after(100.0 * w.before, 100.0 * w.after, "%.0f%%");
}

void print_summary(const JobResult& result) {
  const std::string tilt(1, result.tilt_letter);
  std::printf("%-20s %7s %-26s %-26s %-28s %-28s %-32s %-22s %-9s %-9s %7s %-26s %-26s %7s\n",
              "operation", "points", ("peak omega " + tilt + " deg/s").c_str(),
              "peak omega C deg/s", ("peak a " + tilt + " deg/s^2").c_str(), "peak a C deg/s^2",
              "worst axis (of its limit)", "least cut dia mm", "C jumps", "collide", "dev deg",
              "feed time s", "cycle time s", "time s");
  const auto pair = [](const BeforeAfter<double>& v) {
    return before_after(v.before, v.after, "%.1f");
  };
  const auto count = [](long before, long after) {
    return std::to_string(before) + "->" + std::to_string(after);
  };
  for (const SummaryRow& r : summary_rows(result)) {
    const std::string collide = !result.collision_checked ? std::string("unchecked")
                                : r.colliding_points
                                    ? count(r.colliding_points->before, r.colliding_points->after)
                                    : std::string("-");
    std::printf(
        "%-20.20s %7zu %-26s %-26s %-28s %-28s %-32s %-22s %-9s %-9s %7.2f %-26s %-26s %7.2f\n",
        r.operation.c_str(), r.points, pair(r.peak_omega_tilt_deg_s).c_str(),
        pair(r.peak_omega_c_deg_s).c_str(), pair(r.peak_accel_tilt_deg_s2).c_str(),
        pair(r.peak_accel_c_deg_s2).c_str(), worst_axis_cell(r).c_str(),
        r.least_cutting_diameter_mm ? before_after(r.least_cutting_diameter_mm->before,
                                                   r.least_cutting_diameter_mm->after, "%.2f")
                                          .c_str()
                                    : "-",
        count(r.c_jumps.before, r.c_jumps.after).c_str(), collide.c_str(), r.max_axis_change_deg,
        pair(r.feed_time_s).c_str(), pair(r.cycle_time_s).c_str(), r.compute_s);
  }
}

void print_messages(const JobResult& result, const Toolpath& toolpath, const Args& a) {
  // Errors first (the first 10; -v all of them), then how the file was read, then warnings.
  const std::size_t shown = a.verbose > 0 ? result.problems.size() : 10;
  for (std::size_t i = 0; i < result.problems.size() && i < shown; ++i) {
    std::cerr << "taxopt: error: " << result.problems[i] << "\n";
  }
  if (result.problems.size() > shown) {
    std::cerr << "taxopt: error: ... and " << result.problems.size() - shown
              << " more (-v lists them all)\n";
  }
  // What was not checked first (even with -q: -q silences progress and notes, never a
  // safety warning), then how the file was read, then the other warnings.
  for (const auto& w : result.safety_warnings) {
    std::cerr << "taxopt: warning: NOT CHECKED: " << w << "\n";
  }
  if (!a.quiet) {
    for (const auto& n : toolpath.notices) std::cerr << "taxopt: note: " << n << "\n";
    for (const auto& w : result.warnings) std::cerr << "taxopt: warning: " << w << "\n";
    if (a.verbose > 0) {
      // Each stage's own time over all operations (the report's timings_s per operation).
      double t[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
      for (const auto& r : result.operations) {
        t[0] += r.time_contacts_s;
        t[1] += r.time_cspace_s;
        t[2] += r.time_optimise_s;
        t[3] += r.time_post_s;
        t[4] += r.time_verify_s;
      }
      std::fprintf(stderr,
                   "taxopt: stage times: contacts %.2f s, cspace %.2f s, optimise %.2f s, "
                   "post %.2f s, verify %.2f s\n",
                   t[0], t[1], t[2], t[3], t[4]);
      for (const auto& [word, count] : toolpath.skipped_records) {
        std::cerr << "taxopt: note: " << count << " " << word
                  << " record(s) skipped (no motion), kept for --out-cls\n";
      }
    }
  }
  // Records skipped by --skip-record are said even with -q: the user decided, the program
  // lacks them (this loop sat inside the -q test, silent there, as docs/cli.md says it is not).
  for (const auto& [word, count] : toolpath.skipped_by_option) {
    std::cerr << "taxopt: note: " << count << " " << word
              << " record(s) skipped as asked (--skip-record " << word << ")\n";
  }
}

}  // namespace taxopt::cli
