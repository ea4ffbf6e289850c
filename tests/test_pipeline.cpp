// The stages of a run called one by one (src/pipeline/stages.hpp), and plan_axes:
// the axes a post-processor gets without G-code are the ones run_job writes. On seeded random
// heightfield parts no test was tuned on; every stage's output is checked for the property it
// promises, not for numbers.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "pipeline/stages.hpp"
#include "plan/slerp.hpp"
#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

TEST_CASE(
    "pipeline: each stage called on its own keeps its promise -- contacts touch, planned axes "
    "stay in the cone and miss the part, poses give the axes, the program read back is what "
    "was posted, and verification finds it collision-free",
    "[pipeline][stages]") {
  std::mt19937 rng(4242);
  for (const Heightfield& hf : random_heightfields(rng)) {
    INFO(hf.name);
    const GeneratedCl g = raster_cl(hf, 3.0, 10.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
    const Toolpath tp = parse_cl(g.text, "p.cls");
    const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));
    const Machine machine = default_machine();
    JobOptions given;
    given.part = &part;
    given.method = Method::Global;
    given.paper.grid_deg = 4.0;
    given.max_deviation_deg = 12.0;

    JobResult res;
    pipeline::Run run = pipeline::validate(tp, machine, given, res);
    CHECK(res.has(FindingCode::NoHolderModel));
    CHECK(run.options.paper.max_deviation_deg == 12.0);
    std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
    REQUIRE(ops.size() == tp.operations.size());
    for (const pipeline::OperationContext& o : ops) CHECK(o.ball_radius_mm == Approx(3.0));

    // Contacts: every feed point touches the part where the generator put the contact.
    pipeline::recover_contacts(run, ops, res);
    REQUIRE(run.collision);
    REQUIRE(run.checker);
    std::size_t goto_index = 0;
    for (const pipeline::OperationContext& o : ops) {
      REQUIRE(o.contact.recovered);
      REQUIRE(o.tool);
      REQUIRE(o.real_tool);
      CHECK(o.contact.touching > 0);
      for (std::size_t i = 0; i < o.op->points.size(); ++i, ++goto_index) {
        if (o.op->points[i].motion != Motion::Feed) continue;
        REQUIRE(o.contacts[i].state == ContactState::Touching);
        // The mesh's exact nearest point; against the generator's analytic contact it errs as
        // the mesh's normal does there (C - R N against C - R N_true).
        const Vec3d centre = g.centres_mm[goto_index];
        const Vec3d n_true = (centre - g.cc_mm[goto_index]).normalized();
        const double n_err = angle_between(o.contacts[i].normal, n_true);
        CHECK((o.contacts[i].cc_mm - g.cc_mm[goto_index]).norm() <
              2.0 * 3.0 * std::sin(0.5 * n_err) + 0.01);
        CHECK(rad_to_deg(n_err) < 5.0);
      }
    }

    // Plan: within the cone, and the tool above the ball misses the part at every point
    // (judged by FCL, not by the planner's own check).
    pipeline::plan_operations(run, ops, res);
    for (const pipeline::OperationContext& o : ops) {
      REQUIRE(o.optimised);
      const Operationd& op = *o.op;
      REQUIRE(o.optimised->axes.size() == op.points.size());
      for (std::size_t i = 0; i < op.points.size(); ++i) {
        const Vec3d& v = o.optimised->axes[i];
        CHECK(rad_to_deg(angle_between(v, op.points[i].axis)) <= 12.0 + 1e-6);
        const bool in_air = o.contacts[i].state != ContactState::Touching;
        CHECK_FALSE(run.collision->collides(*o.tool, op.points[i].tip_mm + 3.0 * op.points[i].axis,
                                            v, in_air));
      }
    }

    // Post: the poses give the planned axes, within the machine's ranges; the ball centres
    // stay where the CL file put them.
    std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, res);
    REQUIRE(posted);
    for (std::size_t k = 0; k < ops.size(); ++k) {
      const PostedOperation& po = (*posted)[k];
      const Operationd& op = *ops[k].op;
      for (std::size_t i = 0; i < po.points.size(); ++i) {
        CHECK(angle_between(machine.rotary.forward(po.poses[i]), po.points[i].axis) < 1e-9);
        CHECK(machine.rotary.tilt.contains(po.poses[i].tilt_rad));
        const Vec3d centre_in = op.points[i].tip_mm + 3.0 * op.points[i].axis;
        const Vec3d centre_out = po.points[i].tip_mm + 3.0 * po.points[i].axis;
        CHECK((centre_in - centre_out).norm() < 1e-9);
      }
    }

    // Write: every point's move read back is the posted pose and tip, to the written decimals.
    const pipeline::Written w = pipeline::write_program(run, ops, *posted, res);
    const double half_unit = 0.5 * std::pow(10.0, -machine.gcode.decimals);
    for (std::size_t k = 0; k < ops.size(); ++k) {
      const PostedOperation& po = (*posted)[k];
      REQUIRE(w.point_moves[k].size() == po.points.size());
      for (std::size_t i = 0; i < po.points.size(); ++i) {
        const GcodeMove& m = *w.point_moves[k][i];
        CHECK(std::abs(m.tilt_deg - rad_to_deg(po.poses[i].tilt_rad)) <= half_unit + 1e-9);
        CHECK(std::abs(m.c_deg - rad_to_deg(po.poses[i].c_rad)) <= half_unit + 1e-9);
        CHECK((m.xyz_mm - po.points[i].tip_mm).norm() <= std::sqrt(3.0) * half_unit + 1e-9);
      }
      CHECK(w.schedule_after[k].summary.cycle_time_s > 0.0);
    }

    // Verify: the written program is collision-free by FCL, within the cone and the ranges.
    pipeline::verify_operations(run, ops, *posted, w, res);
    REQUIRE(res.operations.size() == ops.size());
    for (const OperationResult& r : res.operations) {
      CHECK(r.verification.collision_free);
      CHECK(r.verification.within_axis_limits);
      CHECK(r.max_axis_change_deg <= 12.0 + 1e-6);
    }
    CHECK_FALSE(res.out_cls.empty());
  }
}

TEST_CASE(
    "plan_axes: a post-processor gets, without G-code, the axes and poses run_job writes, and "
    "the same findings up to posting",
    "[pipeline][plan_axes]") {
  std::mt19937 rng(777);
  const std::vector<Heightfield> parts = random_heightfields(rng);
  const Machine machine = default_machine();
  for (std::size_t h = 0; h < 2 && h < parts.size(); ++h) {
    const Heightfield& hf = parts[h];
    const GeneratedCl g = raster_cl(hf, 3.0, 15.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
    const Toolpath tp = parse_cl(g.text, "p.cls");
    const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));
    for (const Method method : {Method::Paper, Method::Global}) {
      INFO(hf.name << ", " << to_string(method));
      JobOptions options;
      options.part = &part;
      options.method = method;
      options.paper.grid_deg = 4.0;
      const AxisPlan plan = plan_axes(tp, machine, options);
      const JobResult job = run_job(tp, machine, options);
      REQUIRE(plan.ok());
      REQUIRE(plan.operations.size() == job.operations.size());
      REQUIRE(plan.contacts.size() == tp.operations.size());
      const double half_unit = 0.5 * std::pow(10.0, -machine.gcode.decimals);
      bool turned = false;
      for (std::size_t k = 0; k < plan.operations.size(); ++k) {
        const PostedOperation& po = plan.operations[k];
        const OperationResult& r = job.operations[k];
        REQUIRE(po.points.size() == r.rows.size());
        CHECK(plan.contacts[k].size() == po.points.size());
        for (std::size_t i = 0; i < po.points.size(); ++i) {
          CHECK((po.points[i].axis - r.rows[i].axis).norm() == 0.0);
          CHECK((po.points[i].tip_mm - r.rows[i].tip_mm).norm() == 0.0);
          CHECK(std::abs(rad_to_deg(po.poses[i].tilt_rad) - r.rows[i].tilt_axis_deg) <=
                half_unit + 1e-9);
          CHECK(std::abs(rad_to_deg(po.poses[i].c_rad) - r.rows[i].c_deg) <= half_unit + 1e-9);
          turned = turned || angle_between(po.points[i].axis, tp.operations[k].points[i].axis) >
                                 deg_to_rad(0.5);
        }
      }
      CHECK(turned);  // the method did change axes: the comparison is not of the input's
      // The findings up to posting are run_job's first ones, in order.
      REQUIRE(plan.findings.size() <= job.findings.size());
      for (std::size_t f = 0; f < plan.findings.size(); ++f) {
        CHECK(plan.findings[f].code == job.findings[f].code);
        CHECK(plan.findings[f].message == job.findings[f].message);
      }
    }
  }

  // An unreachable pose: no operations, a problem naming the line.
  const GeneratedCl g = raster_cl(parts.front(), 3.0, 20.0, 1, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  const Toolpath tp = parse_cl(g.text, "p.cls");
  Machine narrow = machine;
  narrow.rotary.tilt.min_rad = deg_to_rad(-5.0);
  narrow.rotary.tilt.max_rad = deg_to_rad(5.0);
  JobOptions options;
  options.method = Method::None;
  const AxisPlan bad = plan_axes(tp, narrow, options);
  CHECK_FALSE(bad.ok());
  CHECK(bad.operations.empty());
  bool named = false;
  for (const Finding& f : bad.findings) {
    named = named || (f.code == FindingCode::UnreachablePose && f.line > 0);
  }
  CHECK(named);
  // Options the library cannot apply are refused before any work, in the library's words
  // (the JobOptions field), not the CLI's.
  options.paper.grid_deg = 0.0;
  CHECK_THROWS_AS(plan_axes(tp, machine, options), InputError);
  CHECK_THROWS_WITH(plan_axes(tp, machine, options),
                    Catch::Contains("JobOptions::paper.grid_deg") && !Catch::Contains("--"));
  options.paper.grid_deg = 2.0;
  options.max_deviation_deg = 95.0;
  CHECK_THROWS_WITH(plan_axes(tp, machine, options),
                    Catch::Contains("JobOptions::max_deviation_deg") && Catch::Contains("95"));
}

TEST_CASE(
    "resolved options: a library caller gets the machine file's holder and clearances without "
    "the CLI, options override them, and the report records the cone and clearances the run "
    "applied",
    "[pipeline][options][report]") {
  std::mt19937 rng(9191);
  const Heightfield hf = random_heightfields(rng).front();
  const GeneratedCl g = raster_cl(hf, 3.0, 15.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  const Toolpath tp = parse_cl(g.text, "p.cls");
  const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));

  Machine shop = default_machine();
  shop.holder_radius_mm = 12.0;
  shop.holder_length_mm = 40.0;
  shop.holder_gauge_length_mm = 35.0;
  shop.shank_clearance_mm = 0.8;
  shop.holder_clearance_mm = 2.5;

  JobOptions given;
  given.part = &part;
  given.method = Method::Paper;
  given.paper.grid_deg = 4.0;
  const JobOptions applied = resolved_options(given, shop);
  REQUIRE(applied.tool.holder_radius_mm);
  CHECK(*applied.tool.holder_radius_mm == 12.0);
  CHECK(*applied.tool.holder_length_mm == 40.0);
  CHECK(*applied.tool.gauge_length_mm == 35.0);
  CHECK(*applied.shank_clearance_mm == 0.8);
  CHECK(*applied.holder_clearance_mm == 2.5);
  // The options win over the machine file; without either, the library's defaults.
  JobOptions own = given;
  own.shank_clearance_mm = 0.1;
  own.tool.holder_radius_mm = 9.0;
  const JobOptions mine = resolved_options(own, shop);
  CHECK(*mine.shank_clearance_mm == 0.1);
  CHECK(*mine.holder_clearance_mm == 2.5);
  CHECK(*mine.tool.holder_radius_mm == 9.0);
  CHECK_FALSE(mine.tool.holder_length_mm);  // a holder named by the options is theirs alone
  const JobOptions bare = resolved_options(given, default_machine());
  CHECK(*bare.shank_clearance_mm == kDefaultShankClearanceMm);
  CHECK(*bare.holder_clearance_mm == kDefaultHolderClearanceMm);
  CHECK_FALSE(bare.tool.holder_radius_mm);

  // A run on the shop machine checks the holder (no "no holder model" warning) and gives the
  // same axes as the same holder and clearances given as options on a bare machine.
  const JobResult on_shop = run_job(tp, shop, given);
  const JobResult as_options = run_job(tp, default_machine(), applied);
  CHECK_FALSE(on_shop.has(FindingCode::NoHolderModel));
  CHECK(run_job(tp, default_machine(), given).has(FindingCode::NoHolderModel));
  REQUIRE(on_shop.operations.size() == as_options.operations.size());
  for (std::size_t k = 0; k < on_shop.operations.size(); ++k) {
    REQUIRE(on_shop.operations[k].rows.size() == as_options.operations[k].rows.size());
    for (std::size_t i = 0; i < on_shop.operations[k].rows.size(); ++i) {
      CHECK((on_shop.operations[k].rows[i].axis - as_options.operations[k].rows[i].axis).norm() ==
            0.0);
    }
  }
  const auto rep = nlohmann::json::parse(report_json(on_shop, tp, shop, given));
  CHECK(rep["clearances_mm"]["shank"] == 0.8);
  CHECK(rep["clearances_mm"]["holder"] == 2.5);
  CHECK(rep["clearances_mm"]["holder_modelled"] == true);

  // Without a part the run keeps to the narrow cone, and the report says so: every written axis
  // is within the reported deviation of the CL file's.
  JobOptions no_part;
  no_part.method = Method::Paper;
  no_part.paper.grid_deg = 0.5;
  const JobResult blind = run_job(tp, default_machine(), no_part);
  const auto blind_rep = nlohmann::json::parse(report_json(blind, tp, default_machine(), no_part));
  const double reported_deg = blind_rep["options"]["max_deviation_deg"].get<double>();
  CHECK(reported_deg == kNoPartMaxDeviationDeg);
  for (std::size_t k = 0; k < blind.operations.size(); ++k) {
    for (std::size_t i = 0; i < blind.operations[k].rows.size(); ++i) {
      CHECK(rad_to_deg(angle_between(blind.operations[k].rows[i].axis,
                                     tp.operations[k].points[i].axis)) <= reported_deg + 1e-6);
    }
  }
}

namespace {

/// One pass of a real 5-axis finish's two troubles (a real NX program): the tool
/// nearly horizontal (tilt `tilt_deg`) turning by 90 deg round a tight fillet over `fillet_mm`
/// -- C turning fast, which no axis in a 1 deg cone can slow much -- then the axis brought up
/// to pass the pole twice at `offset_deg`, where the machine turns C by about 180 deg in a few
/// points: flips a 1 deg deviation removes (through the pole with C held). Flat, no part.
std::string fillet_and_flips_cl(double tilt_deg, double fillet_mm, double offset_deg) {
  std::vector<std::pair<double, Vec3d>> pts;
  const double step = 0.5, tilt = deg_to_rad(tilt_deg);
  for (int k = 0; k <= 20; ++k) {
    const double s = k * step;
    const double phi = deg_to_rad(90.0) * std::clamp((s - 3.5) / fillet_mm, 0.0, 1.0);
    pts.push_back(
        {s, Vec3d(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi), std::cos(tilt))});
  }
  const auto graze = [&](double tilt_y_deg, double off_deg) {
    return Vec3d(std::tan(deg_to_rad(tilt_y_deg)), std::tan(deg_to_rad(off_deg)), 1.0).normalized();
  };
  const Vec3d from = pts.back().second, to = graze(-10.0, offset_deg);
  for (int k = 1; k <= 20; ++k) pts.push_back({10.0 + k * step, slerp(from, to, k / 20.0)});
  for (int k = 1; k <= 40; ++k)
    pts.push_back({20.0 + k * step, graze(-10.0 + k * step, offset_deg)});
  for (int k = 1; k <= 40; ++k)
    pts.push_back({40.0 + k * step, graze(10.0 - k * step, -offset_deg)});
  std::ostringstream cl;
  cl << "TOOL PATH/FLIPS,TOOL,BALL_MILL_D6\nTLDATA/MILL,6.0000,3.0000,15.0000,0.0000,0.0000\n"
        "LOAD/TOOL,1\nSPINDL/RPM,3000.0,CLW\nRAPID\nGOTO/0.000000,0.000000,20.000000,0,0,1\n"
        "FEDRAT/MMPM,1000.0000\n";
  char line[160];
  for (const auto& [x, a] : pts) {
    std::snprintf(line, sizeof line, "GOTO/%.6f,0.000000,0.000000,%.9f,%.9f,%.9f\n", x, a.x(),
                  a.y(), a.z());
    cl << line;
  }
  std::snprintf(line, sizeof line, "RAPID\nGOTO/%.6f,0.000000,20.000000,0,0,1\nEND-OF-PATH\n",
                pts.back().first);
  cl << line;
  return cl.str();
}

}  // namespace

TEST_CASE(
    "optimisers: C flips beside the pole in a pass that also turns a near-horizontal tool "
    "round a tight fillet: the global method removes them, the paper method spreads them, "
    "within the 1 deg cone, the peak a never raised",
    "[pipeline][guard][flips]") {
  std::mt19937 rng(2020);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cases = 0;
  for (int trial = 0; trial < 3; ++trial) {
    const double tilt = 70.0 + 10.0 * u(rng), fillet = 2.0 + 2.0 * u(rng),
                 offset = 0.3 + 0.4 * u(rng);
    const Toolpath tp = parse_cl(fillet_and_flips_cl(tilt, fillet, offset), "flips.cls");
    for (Method method : {Method::Paper, Method::Global}) {
      INFO("tilt " << tilt << " deg, fillet " << fillet << " mm, pole passed at " << offset
                   << " deg, " << to_string(method));
      JobOptions options;
      options.method = method;
      const JobResult res = run_job(tp, default_machine(), options);
      REQUIRE(res.ok());
      REQUIRE(res.operations.size() == 1);
      const OperationResult& op = res.operations[0];
      // Between neighbours whose input axes are within 2 deg of the pole: the steps of C of
      // more than 30 deg (a flip), and the largest step.
      int flips_before = 0, flips_after = 0;
      double step_before = 0.0, step_after = 0.0;
      for (std::size_t i = 1; i < op.rows.size(); ++i) {
        const PointRow &p = op.rows[i - 1], &q = op.rows[i];
        const double from_pole = std::acos(std::min(1.0, tp.operations[0].points[i].axis.z()));
        if (from_pole >= deg_to_rad(2.0)) continue;
        flips_before += std::abs(q.c_before_deg - p.c_before_deg) > 30.0;
        flips_after += std::abs(q.c_deg - p.c_deg) > 30.0;
        step_before = std::max(step_before, std::abs(q.c_before_deg - p.c_before_deg));
        step_after = std::max(step_after, std::abs(q.c_deg - p.c_deg));
      }
      INFO("flips " << flips_before << " -> " << flips_after << ", largest C step " << step_before
                    << " -> " << step_after << " deg, peak a " << op.before.max_accel_deg_s2
                    << " -> " << op.after.max_accel_deg_s2);
      CHECK(flips_before >= 2);
      if (method == Method::Global) {
        CHECK(flips_after == 0);  // through the pole, C held
      } else {
        CHECK(step_after < 0.8 * step_before);  // C re-planned over the stretch (Affouard)
      }
      CHECK(op.after.max_accel_deg_s2 <= op.before.max_accel_deg_s2 * (1.0 + 1e-9));
      CHECK(op.max_axis_change_deg <= kNoPartMaxDeviationDeg + 1e-6);
      ++cases;
    }
  }
  CHECK(cases == 6);
}

TEST_CASE(
    "pipeline: an operation whose paper plan the verification refused is planned again with "
    "the global method's plan (or the input's where free), and says so",
    "[pipeline][stages][fallback]") {
  std::mt19937 rng(34);
  const Heightfield hf = random_heightfields(rng)[0];
  const GeneratedCl g = raster_cl(hf, 3.0, 10.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  const Toolpath tp = parse_cl(g.text, "p.cls");
  const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));
  const Machine machine = default_machine();
  JobOptions given;
  given.part = &part;
  given.method = Method::Paper;
  given.paper.grid_deg = 4.0;
  JobResult res;
  pipeline::Run run = pipeline::validate(tp, machine, given, res);
  run.refused_operations = {0};  // as run_job does after a refused first run
  std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
  pipeline::recover_contacts(run, ops, res);
  pipeline::plan_operations(run, ops, res);
  bool said = false;
  for (const Finding& f : res.findings) {
    said = said || (f.code == FindingCode::InputAxesKept &&
                    f.message.find("the verification refused the paper method's plan") !=
                        std::string::npos);
  }
  CHECK(said);
  std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, res);
  REQUIRE(posted);
  const pipeline::Written w = pipeline::write_program(run, ops, *posted, res);
  pipeline::verify_operations(run, ops, *posted, w, res);
  for (const OperationResult& r : res.operations) CHECK(r.verification.collision_free);
}

TEST_CASE(
    "pipeline: every block of the program is swept against the part -- the blocks taxopt adds "
    "to approach an operation, moved into the part, fail the verification naming their G-code "
    "line, and the untouched program passes",
    "[pipeline][stages][safety]") {
  std::mt19937 rng(77);
  const Heightfield hf = random_heightfields(rng)[0];
  const GeneratedCl g = raster_cl(hf, 3.0, 10.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0);
  Toolpath tp = parse_cl(g.text, "p.cls");
  REQUIRE(tp.operations.size() == 1);
  // Two operations: the blocks between them (retract, turn, descent, XY) are the writer's own.
  tp.operations.push_back(tp.operations.front());
  tp.operations.back().name = "SECOND";
  const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));
  const Machine machine = default_machine();
  REQUIRE(machine.gcode.dialect == GcodeDialect::LinuxCNC);
  JobOptions given;
  given.part = &part;
  given.method = Method::None;
  JobResult clean;
  pipeline::Run run = pipeline::validate(tp, machine, given, clean);
  std::vector<pipeline::OperationContext> ops = pipeline::operation_contexts(run);
  pipeline::recover_contacts(run, ops, clean);
  pipeline::plan_operations(run, ops, clean);
  std::optional<std::vector<PostedOperation>> posted = pipeline::post_operations(run, ops, clean);
  REQUIRE(posted);
  pipeline::Written w = pipeline::write_program(run, ops, *posted, clean);
  const JobResult written = clean;
  pipeline::verify_operations(run, ops, *posted, w, clean);
  for (const Finding& f : clean.findings) UNSCOPED_INFO(f.message);
  CHECK_FALSE(clean.has(FindingCode::MoveCollision));
  long swept = 0;
  for (const OperationResult& r : clean.operations) {
    CHECK(r.verification.colliding_blocks == 0);
    swept += r.verification.blocks_swept.value();
  }
  CHECK(swept >= 2);  // each operation's approach to its first point, the second's XY move

  std::vector<std::string> lines;
  {
    std::istringstream text(written.gcode.text);
    for (std::string l; std::getline(text, l);) lines.push_back(l);
  }
  const auto line_of = [&](const std::string& prefix, std::size_t after) {
    for (std::size_t i = after; i < lines.size(); ++i) {
      if (lines[i].rfind(prefix, 0) == 0) return i + 1;
    }
    return std::size_t{0};
  };
  const std::size_t second = line_of("(operation SECOND)", 0);
  REQUIRE(second > 0);
  // The second operation's approach: the XY move at the clearance height, then the block down
  // to its first point (both written in the workpiece with TCP on).
  const std::size_t xy = line_of("G0 X", second);
  REQUIRE(xy > 0);
  const std::size_t down = xy + 1;
  // A tip 5 mm under the lowest tip the CL file has: the shank crosses the part's surface.
  double lowest = 1e9;
  for (const CLPointd& p : tp.operations.front().points) lowest = std::min(lowest, p.tip_mm.z());
  std::ostringstream z;
  z << std::fixed << std::setprecision(4) << " Z" << lowest - 5.0;
  const auto with_z = [&](std::size_t line) {
    std::string block = lines.at(line - 1);
    const std::size_t at = block.find(" Z");
    if (at == std::string::npos) return block + z.str();
    const std::size_t end = block.find(' ', at + 1);
    return block.substr(0, at) + z.str() + (end == std::string::npos ? "" : block.substr(end));
  };
  struct Tamper {
    const char* what;
    std::size_t line;  // 1-based
    std::string block;
    const char* kind;  // as the finding names the writer's block (GcodeProgram::blocks)
  };
  // The retract between the operations (the first G53 of the second) and the end's turn of
  // the rotaries home (the last block that gives A and C).
  const std::size_t retract = line_of("G53 G0 Z", second);
  std::size_t home = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("G0 A", 0) == 0) home = i + 1;
  }
  REQUIRE(retract > 0);
  REQUIRE(home > second);
  // The retract turned into a move down in the workpiece; the home turn made at a height
  // inside the part, over the first operation's last point.
  const CLPointd& last = tp.operations.front().points.back();
  std::ostringstream end_xy;
  end_xy << std::fixed << std::setprecision(4) << "G0 X" << last.tip_mm.x() << " Y"
         << last.tip_mm.y();
  const std::vector<Tamper> tampers = {
      {"the approach's XY move at the clearance height", xy, with_z(xy), "the approach"},
      {"the approach's block down to the first point", down, with_z(down),
       "a rapid at a joint-safe feed"},
      {"the retract between the operations", retract, "G0" + z.str(), "the retract"},
      {"the end's turn of the rotaries home", home,
       end_xy.str() + z.str() + lines.at(home - 1).substr(2), "the program's end"},
  };
  for (const Tamper& t : tampers) {
    INFO(t.what << ": G-code line " << t.line << " '" << lines.at(t.line - 1) << "' -> '" << t.block
                << "'");
    REQUIRE(t.line > 0);
    JobResult res = written;
    std::vector<std::string> changed = lines;
    changed[t.line - 1] = t.block;
    res.gcode.text.clear();
    for (const std::string& l : changed) res.gcode.text += l + "\n";
    pipeline::read_program_again(run, *posted, w, res);
    pipeline::verify_operations(run, ops, *posted, w, res);
    bool named = false;
    for (const Finding& f : res.findings) {
      INFO(f.message);
      // The G-code line apart from the CL line: a block the writer added has none of the latter.
      named = named || (f.code == FindingCode::MoveCollision &&
                        f.message.find("G-code line " + std::to_string(t.line) + " (" + t.kind +
                                       ", ") != std::string::npos &&
                        f.gcode_line == t.line && f.line == 0);
    }
    CHECK(named);
    CHECK_FALSE(res.problems.empty());
  }
}

TEST_CASE(
    "pipeline: every method keeps its promise per rotary axis -- where the input is free no "
    "axis's peak omega or a rises above the input's, the kept counts are the axes written as "
    "the input's, and the least tilt from the normal, asked or the input's own, is held where the "
    "input keeps it",
    "[pipeline][promise]") {
  std::mt19937 rng(59);
  const std::vector<Heightfield> parts = random_heightfields(rng);
  for (std::size_t h = 0; h < 2 && h < parts.size(); ++h) {
    const Heightfield& hf = parts[h];
    INFO(hf.name);
    // Two operations of one job: a pass led 5 deg and one led 12 deg off the normal.
    Toolpath tp =
        parse_cl(raster_cl(hf, 3.0, 5.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0).text, "p.cls");
    const Toolpath second =
        parse_cl(raster_cl(hf, 3.0, 12.0, 2, 0.5, 20.0, 30.0, 5.0, 45.0, 80.0).text, "q.cls");
    tp.operations.push_back(second.operations.front());
    tp.operations.back().name = "SECOND";
    const Part part(heightfield_mesh(hf, 0.5, 0.0, 50.0, 10.0, 40.0));
    Machine machine = default_machine();
    machine.limits[static_cast<std::size_t>(Joint::Tilt)] = {100.0, 1000.0, 0.0};
    machine.limits[static_cast<std::size_t>(Joint::C)] = {200.0, 2000.0, 0.0};
    for (const bool global : {false, true}) {
      for (const bool tilt : {false, true}) {
        INFO("global " << global << ", least tilt asked " << tilt);
        JobOptions options;
        options.part = &part;
        options.method = global ? Method::Global : Method::Paper;
        options.paper.grid_deg = 4.0;
        if (tilt) options.min_tilt_deg = 4.0;
        const JobResult res = run_job(tp, machine, options);
        REQUIRE(res.operations.size() == 2);
        for (std::size_t k = 0; k < res.operations.size(); ++k) {
          const OperationResult& r = res.operations[k];
          const Operationd& op = tp.operations[k];
          INFO(r.name);
          REQUIRE(r.colliding_before);
          REQUIRE(r.worst_axis);  // the machine gives both rotary limits
          if (*r.colliding_before == 0) {
            CHECK(r.after.tilt.max_omega_deg_s <=
                  std::max(r.before.tilt.max_omega_deg_s * 1.001, pipeline::kStillOmegaDegS));
            CHECK(r.after.c.max_omega_deg_s <=
                  std::max(r.before.c.max_omega_deg_s * 1.001, pipeline::kStillOmegaDegS));
            CHECK(r.after.tilt.max_accel_deg_s2 <=
                  std::max(r.before.tilt.max_accel_deg_s2 * 1.001, pipeline::kStillAccelDegS2));
            CHECK(r.after.c.max_accel_deg_s2 <=
                  std::max(r.before.c.max_accel_deg_s2 * 1.001, pipeline::kStillAccelDegS2));
            CHECK_FALSE(res.has(FindingCode::AxisRateRose));
          }
          // Kept counts: the feed passes' points written with their input axes.
          REQUIRE(r.kept_input_points);
          std::size_t written_as_input = 0;
          for (const IndexRange& pass : feed_passes(op)) {
            for (std::size_t i = pass.begin; i < pass.end; ++i) {
              written_as_input += angle_between(r.rows[i].axis, op.points[i].axis) <= 1e-6;
            }
          }
          CHECK(r.kept_input_points->total() == written_as_input);
          REQUIRE(r.cutting);
          // Asked (4 deg) or by default (the input's own least, rounded down to 0.1 deg), the
          // least tilt is held wherever the input itself keeps it.
          CHECK(r.cutting->least_tilt_given == tilt);
          const double bound_deg = tilt ? 4.0 : r.cutting->least_tilt_deg;
          CHECK(bound_deg >= 1.0);
          CHECK(r.cutting->least_tilt_held);
          CHECK(r.cutting->least_tilt_before_deg >= bound_deg);
          CHECK(r.cutting->points_below == 0);
          CHECK(r.cutting->least_tilt_after_deg >= bound_deg - pipeline::kTiltAllowanceDeg);
        }
      }
    }
  }
}
