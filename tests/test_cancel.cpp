// A job its caller can stop: JobOptions::stop from another thread or from the progress callback
// ends run_job with Cancelled and no result; a progress callback that throws stops the job with
// its own exception (it used to end the process: the callback ran in destructors inside TBB
// tasks); JobOptions::threads is the job's own arena, and the result does not depend on it.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <thread>

#include "support.hpp"
#include "taxopt/core/error.hpp"
#include "taxopt/cspace/cspace.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using namespace taxopt::test;

namespace {

struct Demo {
  Toolpath tp = read_cl_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.cls");
  Part part{read_mesh_file(std::string(TAXOPT_SOURCE_DIR) + "/data/demo/sine.stl")};
  JobOptions options() const {
    JobOptions o;
    o.part = &part;
    o.method = Method::Global;
    return o;
  }
};

}  // namespace

TEST_CASE(
    "cancel: a stop from the progress callback, another thread or before the start ends the job "
    "with Cancelled, and a callback that throws ends it with its own exception",
    "[library][cancel]") {
  const Demo demo;
  // Stopped before it starts.
  {
    JobOptions o = demo.options();
    o.stop.request_stop();
    CHECK_THROWS_AS(run_job(demo.tp, default_machine(), o), Cancelled);
    CHECK_THROWS_AS(plan_axes(demo.tp, default_machine(), o), Cancelled);
  }
  // Stopped by the callback halfway through each long stage: nothing after it runs.
  for (const std::string stage : {"contact recovery", "optimisation", "verification"}) {
    INFO(stage);
    JobOptions o = demo.options();
    std::vector<std::string> seen;
    const StopSource stop = o.stop;
    o.progress = [&](const std::string& s, std::size_t done, std::size_t total) {
      if (seen.empty() || seen.back() != s) seen.push_back(s);
      if (s == stage && 2 * done >= total) stop.request_stop();
    };
    CHECK_THROWS_AS(run_job(demo.tp, default_machine(), o), Cancelled);
    REQUIRE_FALSE(seen.empty());
    CHECK(seen.back() == stage);
  }
  // Inside the verification's sweep of the moves (its third quarter of items): the stop was
  // looked at in a destructor there, and its Cancelled ended the process.
  for (const double share : {0.55, 0.65}) {
    INFO(share);
    JobOptions o = demo.options();
    const StopSource stop = o.stop;
    o.progress = [&](const std::string& s, std::size_t done, std::size_t total) {
      if (s == "verification" && static_cast<double>(done) >= share * static_cast<double>(total)) {
        stop.request_stop();
      }
    };
    CHECK_THROWS_AS(run_job(demo.tp, default_machine(), o), Cancelled);
  }
  // A callback that throws: its exception, the process alive, nothing after it run.
  {
    JobOptions o = demo.options();
    int calls_after = 0;
    bool thrown = false;
    o.progress = [&](const std::string& s, std::size_t done, std::size_t total) {
      if (thrown) ++calls_after;
      if (s == "optimisation" && 4 * done >= total && !thrown) {
        thrown = true;
        throw std::runtime_error("the post's own error");
      }
    };
    CHECK_THROWS_WITH(run_job(demo.tp, default_machine(), o), "the post's own error");
    CHECK(calls_after == 0);
  }
  // From another thread, while it runs.
  {
    JobOptions o = demo.options();
    const StopSource stop = o.stop;
    std::atomic<bool> started{false};
    o.progress = [&](const std::string&, std::size_t, std::size_t) { started = true; };
    std::thread stopper([&] {
      while (!started) std::this_thread::yield();
      stop.request_stop();
    });
    CHECK_THROWS_AS(run_job(demo.tp, default_machine(), o), Cancelled);
    stopper.join();
  }
}

TEST_CASE(
    "cancel: JobOptions::threads runs the job in its own arena: 1, 2 and all cores, and two jobs "
    "at once in two threads, give the same bytes",
    "[library][threads]") {
  const Demo demo;
  std::vector<std::string> programs;
  for (std::size_t threads : {std::size_t(1), std::size_t(2), std::size_t(0)}) {
    JobOptions o = demo.options();
    o.method = Method::Paper;
    o.threads = threads;
    programs.push_back(run_job(demo.tp, default_machine(), o).gcode.text);
  }
  CHECK(programs[0] == programs[1]);
  CHECK(programs[0] == programs[2]);
  std::string a, b;
  std::thread first([&] {
    JobOptions o = demo.options();
    o.method = Method::Paper;
    o.threads = 1;
    a = run_job(demo.tp, default_machine(), o).gcode.text;
  });
  std::thread second([&] {
    JobOptions o = demo.options();
    o.method = Method::Paper;
    o.threads = 2;
    b = run_job(demo.tp, default_machine(), o).gcode.text;
  });
  first.join();
  second.join();
  CHECK(a == programs[0]);
  CHECK(b == programs[0]);
  JobOptions o = demo.options();
  o.threads = 5000;
  CHECK_THROWS_AS(run_job(demo.tp, default_machine(), o), InputError);
}

TEST_CASE(
    "cancel: contact recovery's progress moves per point -- a one-operation job reports every "
    "whole percent, not 0 then 1",
    "[library][cancel]") {
  const Demo demo;
  REQUIRE(demo.tp.operations.size() == 1);
  JobOptions o = demo.options();
  std::vector<std::size_t> done_seen;
  std::size_t total_seen = 0;
  o.progress = [&](const std::string& s, std::size_t done, std::size_t total) {
    if (s != "contact recovery") return;
    done_seen.push_back(done);
    total_seen = total;
  };
  (void)plan_axes(demo.tp, default_machine(), o);
  CHECK(total_seen == demo.tp.operations[0].points.size());
  CHECK(done_seen.size() == 101);  // 0, each whole percent, the end
  CHECK(std::is_sorted(done_seen.begin(), done_seen.end()));
  CHECK(done_seen.back() == total_seen);
}

TEST_CASE(
    "cancel: building a Part, FCL's model and the rasteriser's tree looks at the stop -- a stop "
    "requested before or while they build ends them with Cancelled, and the same mesh still "
    "builds after",
    "[library][cancel]") {
  // 2 x 300 x 300 faces (a few tenths of a second to build: a stop 5 ms in lands inside).
  Heightfield wavy{"wavy", [](double x, double y) { return std::sin(0.3 * x) * std::cos(0.2 * y); },
                   [](double, double) { return Vec3d::UnitZ(); }};
  const TriangleMesh mesh = heightfield_mesh(wavy, 0.2, 0.0, 60.0, 0.0, 60.0);
  REQUIRE(mesh.faces.size() > 150000);
  StopSource stopped;
  stopped.request_stop();
  CHECK_THROWS_AS(Part(mesh, stopped), Cancelled);
  CHECK_THROWS_AS(CollisionModel(mesh, stopped), Cancelled);
  CHECK_THROWS_AS(CSpaceRasteriser(mesh, stopped), Cancelled);
  // A stop's reason is what the build throws.
  StopSource reasoned;
  reasoned.request_stop(std::make_exception_ptr(std::runtime_error("the user closed the job")));
  CHECK_THROWS_WITH(Part(mesh, reasoned), "the user closed the job");
  const auto stops_midway = [&](const std::function<void(const StopSource&)>& build) {
    StopSource s;
    std::thread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      s.request_stop();
    });
    bool cancelled = false;
    try {
      build(s);
    } catch (const Cancelled&) {
      cancelled = true;
    }
    stopper.join();
    return cancelled;
  };
  CHECK(stops_midway([&](const StopSource& s) { Part p(mesh, s); }));
  CHECK(stops_midway([&](const StopSource& s) { CollisionModel c(mesh, s); }));
  // After a stop the same mesh builds whole, and answers as one built without a stop.
  const Part whole(mesh, StopSource());
  const Part plain(mesh);
  const Vec3d q(30.0, 30.0, 5.0);
  CHECK(whole.closest(q).point == plain.closest(q).point);
  CHECK(whole.chordal_error_mm() == plain.chordal_error_mm());
}
