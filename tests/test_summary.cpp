// The CLI's table and the page's summary read one model (summary_rows): its numbers are the
// report's, operation by operation, and the page shows them.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "support.hpp"
#include "support/html_page.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;

TEST_CASE("summary: the rows the CLI and the page show are the report's numbers", "[report]") {
  const Toolpath tp = read_cl_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls");
  const Part part{read_mesh_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl")};
  for (const bool with_part : {true, false}) {
    INFO((with_part ? "with the part" : "without a part"));
    JobOptions options;
    options.method = Method::Paper;
    if (with_part) options.part = &part;
    const Machine machine = default_machine();
    const JobResult result = run_job(tp, machine, options);
    const std::vector<SummaryRow> rows = summary_rows(result);
    const auto report = nlohmann::json::parse(report_json(result, tp, machine, options));
    REQUIRE(rows.size() == report["operations"].size());
    REQUIRE(!rows.empty());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const SummaryRow& row = rows[k];
      const auto& op = report["operations"][k];
      CHECK(row.operation == op["name"].get<std::string>());
      CHECK(row.points == op["points"].get<std::size_t>());
      for (const auto& [value, key] : {std::make_pair(row.peak_omega_deg_s, "max_omega_deg_s"),
                                       std::make_pair(row.peak_accel_deg_s2, "max_accel_deg_s2"),
                                       std::make_pair(row.rms_accel_deg_s2, "rms_accel_deg_s2"),
                                       std::make_pair(row.feed_time_s, "feed_time_s"),
                                       std::make_pair(row.cycle_time_s, "cycle_time_s")}) {
        INFO(key);
        CHECK(value.before == Approx(op["before"][key].get<double>()).epsilon(1e-11));
        CHECK(value.after == Approx(op["after"][key].get<double>()).epsilon(1e-11));
      }
      CHECK(row.c_jumps.after == op["after"]["c_jumps"].get<long>());
      CHECK(row.colliding_points.has_value() == with_part);
      CHECK(op["after"]["colliding_points"].is_null() == !with_part);
      if (row.colliding_points) {
        CHECK(row.colliding_points->after == op["after"]["colliding_points"].get<long>());
        CHECK(row.colliding_points->before == op["before"]["colliding_points"].get<long>());
      }
      CHECK(row.max_axis_change_deg ==
            Approx(op["max_axis_change_deg"].get<double>()).epsilon(1e-11));
    }
    // The page's summary table shows each row: its name, and "NOT CHECKED" exactly when the
    // rows say no collision check ran.
    const std::string page = html_page(result, tp, machine, options, RunInfo{},
                                       with_part ? &part.mesh() : nullptr, load_html_assets());
    const std::size_t table = page.find("<table class=\"summary\">");
    REQUIRE(table != std::string::npos);
    const std::string summary = page.substr(table, page.find("</table>", table) - table);
    for (const SummaryRow& row : rows) CHECK_THAT(summary, Catch::Contains(row.operation));
    CHECK((summary.find("NOT CHECKED") != std::string::npos) == !with_part);
  }
}
