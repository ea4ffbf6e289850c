// The real-job harness (issue 59): the eight operations of real_job.hpp, every method (the time
// objective too), on an A/C machine and on the Haas UMC-750 (B/C, its limits, the feeds
// scheduled to them, the Haas job's looser contact tolerance), each judged by what is written,
// read back and measured here: each rotary axis's peak omega and a from the blocks' own words
// (the tip path over F, as the controller runs it in TCP), the written axes against the input's
// (the kept counts), the tool's flutes and shank against every triangle near them (a bucketed
// brute force: no FCL, no CGAL, none of taxopt's checks). TAXOPT_REAL_JOB_DIR=folder writes the
// job's CL file and mesh there, to run it with the CLI.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "real_job.hpp"
#include "support.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kBallR = kRealJobBallMm;

/// The part's triangles in cubes of kCellMm, each in every cube its box meets: the triangles
/// within a distance of a point are those of the cubes about it.
class Buckets {
 public:
  static constexpr double kCellMm = 2.0;
  explicit Buckets(const TriangleMesh& mesh) : mesh_(mesh), stamp_(mesh.faces.size(), 0) {
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
      Eigen::Vector3i lo = cell(mesh.vertices[mesh.faces[f][0]]), hi = lo;
      for (int v = 1; v < 3; ++v) {
        const Eigen::Vector3i c = cell(mesh.vertices[mesh.faces[f][v]]);
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
      for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
          for (int z = lo.z(); z <= hi.z(); ++z) cells_[{x, y, z}].push_back(f);
    }
  }
  /// Distance from p to the part, capped at `reach` (nothing nearer: `reach`).
  double distance(const Vec3d& p, double reach) {
    ++round_;
    double best = reach;
    const Eigen::Vector3i lo = cell(p - Vec3d::Constant(reach)),
                          hi = cell(p + Vec3d::Constant(reach));
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const auto it = cells_.find({x, y, z});
          if (it == cells_.end()) continue;
          for (std::size_t f : it->second) {
            if (stamp_[f] == round_) continue;
            stamp_[f] = round_;
            const auto& t = mesh_.faces[f];
            const Vec3d q = closest_on_triangle(p, mesh_.vertices[t[0]], mesh_.vertices[t[1]],
                                                mesh_.vertices[t[2]]);
            best = std::min(best, (q - p).norm());
          }
        }
    return best;
  }

 private:
  static Eigen::Vector3i cell(const Vec3d& p) {
    return (p / kCellMm).array().floor().cast<int>().matrix();
  }
  const TriangleMesh& mesh_;
  std::map<std::array<int, 3>, std::vector<std::size_t>> cells_;
  std::vector<unsigned> stamp_;
  unsigned round_ = 0;
};

}  // namespace

namespace {

/// One program read back: its moves, and the move of each G-code line.
struct ReadBack {
  std::vector<GcodeMove> moves;
  std::map<int, std::size_t> at_line;
};

ReadBack read_back(const JobResult& r, const Machine& machine) {
  ReadBack b;
  b.moves = read_gcode_moves(r.gcode.text, "job.nc", machine.gcode.dialect, r.gcode.verbatim_lines,
                             machine.rotary.tilt_letter(), r.gcode.tool_calls);
  for (std::size_t m = 0; m < b.moves.size(); ++m) b.at_line[b.moves[m].line] = m;
  return b;
}

/// Depths below -kReachMm are all "clear by kReachMm", mm.
constexpr double kReachMm = 1.0;

/// What one operation's written program does, measured on the blocks read back.
struct OpMeasure {
  /// Per rotary axis (tilt, C): peak omega (deg/s), peak a and RMS a (deg/s^2), each block
  /// timed by its own words (the tip path over F, as the controller runs it in TCP).
  double omega[2] = {0, 0}, accel[2] = {0, 0}, rms_accel[2] = {0, 0};
  /// The feed passes' time as the words give it, s.
  double feed_time_s = 0.0;
  /// Feed-pass points written with the input's axis, and the largest turn off it, deg.
  std::size_t kept = 0, points = 0;
  double max_turn_deg = 0.0;
  /// The deepest of depth_mm.
  double deepest_mm = -kReachMm;
  /// Largest distance of a written ball centre from the input's, mm.
  double centre_error_mm = 0.0;
  /// Per point: how deep the flutes and shank reach into the part (body_depth), mm (negative:
  /// their clearance, down to -kReachMm); NaN where not written.
  std::vector<double> depth_mm;
};

/// The written pose of each of operation k's points, from its G-code line (null: not written).
std::vector<const GcodeMove*> written_points(const JobResult& r, const ReadBack& b, std::size_t k,
                                             std::size_t n) {
  std::vector<const GcodeMove*> w(n, nullptr);
  for (std::size_t i = 0; i < n && i < r.gcode.emitted[k].size(); ++i) {
    const auto it = b.at_line.find(r.gcode.emitted[k][i]);
    if (it != b.at_line.end() && !b.moves[it->second].positioning) w[i] = &b.moves[it->second];
  }
  return w;
}

/// Per-axis rates over operation k's feed passes.
void measure_rates(const std::vector<const GcodeMove*>& w, const Operationd& op, OpMeasure& m) {
  double sum_sq[2] = {0, 0};
  std::size_t samples = 0;
  for (const IndexRange& pass : feed_passes(op)) {
    double last_omega[2] = {0, 0}, last_dt = 0.0;
    for (std::size_t i = pass.begin + 1; i < pass.end; ++i) {
      if (!w[i - 1] || !w[i]) {
        last_dt = 0.0;
        continue;
      }
      const double dt = (w[i]->xyz_mm - w[i - 1]->xyz_mm).norm() / w[i]->feed * 60.0;
      if (!(dt > 0.0)) continue;
      m.feed_time_s += dt;
      const double turn[2] = {w[i]->tilt_deg - w[i - 1]->tilt_deg, w[i]->c_deg - w[i - 1]->c_deg};
      for (int ax = 0; ax < 2; ++ax) {
        const double omega = turn[ax] / dt;
        m.omega[ax] = std::max(m.omega[ax], std::abs(omega));
        if (last_dt > 0.0) {
          const double a = (omega - last_omega[ax]) / (0.5 * (dt + last_dt));
          m.accel[ax] = std::max(m.accel[ax], std::abs(a));
          sum_sq[ax] += a * a;
        }
        last_omega[ax] = omega;
      }
      samples += last_dt > 0.0;
      last_dt = dt;
    }
  }
  for (int ax = 0; ax < 2; ++ax)
    m.rms_accel[ax] = samples ? std::sqrt(sum_sq[ax] / static_cast<double>(samples)) : 0.0;
}

/// How deep the flutes and shank reach into the part: the axis from 1 mm above the ball centre
/// (below, the ball's own contact) to 30 mm, grown by R; sampled every 0.25 mm, then every
/// 0.025 mm about the deepest sample (a sphere between samples misses at most 0.0001 mm).
double body_depth(Buckets& buckets, const Vec3d& centre, const Vec3d& axis) {
  const auto at = [&](double h) {
    return kBallR - buckets.distance(centre + h * axis, kBallR + kReachMm);
  };
  double depth = -kReachMm, deepest = 0.1;
  for (double h = 0.1; h <= 30.0; h += 0.25) {
    const double d = at(h);
    if (d > depth) depth = d, deepest = h;
  }
  for (double h = std::max(0.1, deepest - 0.25); h <= deepest + 0.25; h += 0.025) {
    depth = std::max(depth, at(h));
  }
  return depth;
}

/// Operation k of a run, measured on its program read back.
OpMeasure measure(const JobResult& r, const ReadBack& b, std::size_t k, const Operationd& op,
                  const Machine& machine, Buckets& buckets) {
  OpMeasure m;
  const std::vector<const GcodeMove*> w = written_points(r, b, k, op.points.size());
  measure_rates(w, op, m);
  m.depth_mm.assign(op.points.size(), std::nan(""));
  for (const IndexRange& pass : feed_passes(op)) {
    for (std::size_t i = pass.begin; i < pass.end; ++i) {
      REQUIRE(w[i]);
      const Posed pose{w[i]->tilt_deg * kDeg, w[i]->c_deg * kDeg};
      const Vec3d axis = machine.rotary.forward(pose);
      const Vec3d centre = tip_of_written_mm(machine, w[i]->xyz_mm, pose) + kBallR * axis;
      const Vec3d input_centre = op.points[i].tip_mm + kBallR * op.points[i].axis;
      m.centre_error_mm = std::max(m.centre_error_mm, (centre - input_centre).norm());
      const double turn_deg = std::acos(std::min(1.0, axis.dot(op.points[i].axis))) / kDeg;
      ++m.points;
      m.kept += turn_deg < 1e-4;  // the written words' rounding: 0.0001 deg
      m.max_turn_deg = std::max(m.max_turn_deg, turn_deg);
      m.depth_mm[i] = body_depth(buckets, centre, axis);
      m.deepest_mm = std::max(m.deepest_mm, m.depth_mm[i]);
    }
  }
  return m;
}

}  // namespace

namespace {

/// A method as the CLI names it, and how run_job is asked for it.
struct MethodRun {
  const char* name;
  Method method;
  GlobalObjective objective;
};
constexpr MethodRun kMethods[] = {{"paper", Method::Paper, GlobalObjective::SumSquares},
                                  {"global", Method::Global, GlobalObjective::SumSquares},
                                  {"global time", Method::Global, GlobalObjective::Time}};

struct Job {
  TriangleMesh mesh = real_job_part();
  Part part{mesh};
  Toolpath tp = parse_cl(real_job_cl(), "job.cls");
  Buckets buckets{mesh};
};

struct Run {
  JobResult result;
  std::vector<OpMeasure> ops;
};

/// How the job is run besides the method: with the feeds scheduled to the machine's limits (a
/// machine slower than the CAM's feeds), with the Haas job's looser contact tolerance.
struct Setting {
  bool schedule = false;
  double contact_tolerance_mm = 0.0;
};

Run run_method(Job& job, const Machine& machine, const Setting& setting, Method method,
               GlobalObjective objective) {
  JobOptions options;
  options.feed_schedule = setting.schedule;
  options.contact.tolerance_mm = setting.contact_tolerance_mm;
  options.part = &job.part;
  options.method = method;
  options.global.objective = objective;
  Run run{run_job(job.tp, machine, options), {}};
  for (const std::string& p : run.result.problems) UNSCOPED_INFO(p);
  REQUIRE(run.result.ok());
  const ReadBack b = read_back(run.result, machine);
  for (std::size_t k = 0; k < job.tp.operations.size(); ++k) {
    run.ops.push_back(measure(run.result, b, k, job.tp.operations[k], machine, job.buckets));
  }
  return run;
}

constexpr const char* kAxisName[2] = {"tilt", "C"};

/// How deep the tool reaches into the part at operation op's feed points with each input axis
/// turned `turn_deg` toward the part (toward the axis's own foot: against its lean), the deepest.
double deepest_turned(Job& job, const Operationd& op, double turn_deg) {
  double deepest = -kReachMm;
  for (const IndexRange& pass : feed_passes(op)) {
    for (std::size_t i = pass.begin + 1; i < pass.end; ++i) {
      const Vec3d& axis = op.points[i].axis;
      const Vec3d inward = -Vec3d(axis.x(), axis.y(), 0.0).normalized();
      const Vec3d turned = (axis + std::tan(turn_deg * kDeg) * inward).normalized();
      const Vec3d centre = op.points[i].tip_mm + kBallR * axis;
      deepest = std::max(deepest, body_depth(job.buckets, centre, turned));
    }
  }
  return deepest;
}

/// The classes the job is to reproduce, on the input's own program.
void check_classes(Job& job, const Run& input) {
  for (std::size_t k = 0; k < job.tp.operations.size(); ++k) {
    const std::string& name = job.tp.operations[k].name;
    const OpMeasure& m = input.ops[k];
    INFO(name);
    CHECK(input.result.operations[k].colliding_before.value() == 0);
    CHECK(m.centre_error_mm < 1e-3);
    if (name == "CHAMFER") {  // the axes stand still: nothing to gain
      CHECK(m.omega[0] < 0.1);
      CHECK(m.omega[1] < 0.1);
    } else if (name == "ROTARY_FLOOR" || name == "OUTLINE_CHAMFER") {  // the tilt still, C turns
      CHECK(m.omega[0] < 0.1);
      CHECK(m.omega[1] > 1.0);
    } else if (name == "FILLET" || name == "CURVE_FILLET") {
      // The tool's side within 0.3 mm of the part, and 3 deg toward it puts it in.
      CHECK(m.deepest_mm < 0.0);
      CHECK(m.deepest_mm > -0.3);
      CHECK(deepest_turned(job, job.tp.operations[k], 3.0) > 0.05);
    } else {  // the loops: C follows the path's direction
      CHECK(m.omega[1] > 100.0);
    }
  }
}

/// Every promise of a method on every operation, against the input's program.
void check_promises(const Job& job, const Run& input, const Run& run, const Machine& machine,
                    GlobalObjective objective) {
  for (std::size_t k = 0; k < job.tp.operations.size(); ++k) {
    const std::string& name = job.tp.operations[k].name;
    const OpMeasure& before = input.ops[k];
    const OpMeasure& after = run.ops[k];
    const OperationResult& o = run.result.operations[k];
    INFO(name << ": kept " << after.kept << " of " << after.points << ", largest turn "
              << after.max_turn_deg << " deg");
    CHECK(o.colliding_after.value() == 0);
    CHECK(o.verification.colliding_blocks.value() == 0);
    CHECK(after.centre_error_mm < 1e-3);
    // Per axis: no peak omega or a above the input's (the rounding of the words: 0.1 deg/s, 1
    // deg/s^2, the still axis's allowance).
    for (int ax = 0; ax < 2; ++ax) {
      INFO(kAxisName[ax] << ": omega " << before.omega[ax] << " -> " << after.omega[ax] << ", a "
                         << before.accel[ax] << " -> " << after.accel[ax]);
      CHECK(after.omega[ax] <= before.omega[ax] * 1.001 + 0.1);
      CHECK(after.accel[ax] <= before.accel[ax] * 1.001 + 1.0);
    }
    // The kept counts are the axes written.
    REQUIRE(o.kept_input_points);
    CHECK(o.kept_input_points->total() == after.kept);
    // Axes turned gain something the machine feels, on some axis (the time objective: time).
    if (after.max_turn_deg > 1e-3) {
      bool gains =
          objective == GlobalObjective::Time && after.feed_time_s < before.feed_time_s * 0.999;
      for (int ax = 0; ax < 2; ++ax) {
        gains = gains || after.accel[ax] < before.accel[ax] * 0.999 ||
                after.omega[ax] < before.omega[ax] * 0.999 ||
                after.rms_accel[ax] < before.rms_accel[ax] * 0.99;
      }
      CHECK(gains);
    }
    if (name == "CHAMFER") CHECK(after.max_turn_deg < 1e-3);
    // No part of the tool deeper than the input's (0.002 mm: the measure's own error).
    for (std::size_t i = 0; i < after.depth_mm.size(); ++i) {
      if (std::isnan(after.depth_mm[i])) continue;
      INFO("CL point " << i << " (line " << job.tp.operations[k].points[i].line << ")");
      CHECK(after.depth_mm[i] <= std::max(before.depth_mm[i], 0.0) + 0.002);
    }
    // The report names the worst axis against the machine's limit.
    REQUIRE(o.worst_axis);
    CHECK(o.worst_axis->limit > 0.0);
    CHECK(o.worst_axis->axis == (o.worst_axis->axis == 'C' ? 'C' : machine.rotary.tilt_letter()));
  }
}

/// The job on one machine preset: the input's program, then every method's.
void run_real_job(const std::string& preset, const Setting& setting) {
  Job job;
  REQUIRE(job.tp.operations.size() == 8);
  const Machine machine =
      read_machine_file(std::string(TAXOPT_SOURCE_DIR) + "/data/machines/" + preset + ".toml");
  if (const char* dir = std::getenv("TAXOPT_REAL_JOB_DIR")) {
    write_file(std::string(dir) + "/job.cls", real_job_cl());
    write_file(std::string(dir) + "/job.stl", format_stl_binary(job.mesh, "job"));
  }
  const Run input = run_method(job, machine, setting, Method::None, GlobalObjective::SumSquares);
  check_classes(job, input);
  for (const MethodRun& m : kMethods) {
    INFO("method " << m.name << " on " << preset);
    const Run run = run_method(job, machine, setting, m.method, m.objective);
    check_promises(job, input, run, machine, m.objective);
    for (std::size_t k = 0; k < job.tp.operations.size(); ++k) {
      const OpMeasure& a = run.ops[k];
      const OpMeasure& b = input.ops[k];
      std::printf(
          "%-12s %-11s %-14s omega %8.2f %8.2f -> %8.2f %8.2f  a %9.1f %9.1f -> %9.1f "
          "%9.1f  kept %4zu/%4zu  turn %6.2f  deepest %7.3f -> %7.3f  feed %6.2f -> "
          "%6.2f s\n",
          preset.c_str(), m.name, job.tp.operations[k].name.c_str(), b.omega[0], b.omega[1],
          a.omega[0], a.omega[1], b.accel[0], b.accel[1], a.accel[0], a.accel[1], a.kept, a.points,
          a.max_turn_deg, b.deepest_mm, a.deepest_mm, b.feed_time_s, a.feed_time_s);
    }
  }
}

}  // namespace

TEST_CASE(
    "real job: on a CAD-style part of eight operations (chamfers with nothing to gain and round "
    "a block, a 4-axis rotary floor, fillets with the tool's side near the part, ovals and a "
    "circle) every method keeps each rotary axis at or under the input's, counts the axes it "
    "kept, turns none for nothing and puts no part of the tool deeper than the input did, on an "
    "A/C machine",
    "[pipeline][safety][cad][real-job][slow]") {
  run_real_job("generic-ac-trt", {});
}

TEST_CASE(
    "real job: the same eight operations on the Haas UMC-750 (B/C), its limits and the feeds "
    "scheduled to them, each axis against its input and the report's worst axis against the "
    "machine's limits",
    "[pipeline][safety][cad][real-job][slow]") {
  run_real_job("haas-umc750", {true, 0.1});
}
