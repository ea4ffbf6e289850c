// How long a stop takes to be honoured (issue 64): a StopSource's request_stop from another
// thread, at several moments of building a Part and of run_job (its set-up, contact recovery
// with FCL's model built beside it, the stages after), to the Cancelled the caller catches.
// Run: build/release/bench/bench_stop CL_FILE MESH_FILE [Part delays in s, comma-separated]
// [moments of run_job, spread evenly over its run; 24]
// e.g. taxopt generate --surface sine --width 200 --length 590 --mesh-step 0.75 --out-cls
// big.cls --out-mesh big.stl, then bench_stop big.cls big.stl
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "taxopt/geometry/part.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"
#include "taxopt/job.hpp"

using namespace taxopt;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

struct Latency {
  bool stopped = false;  // Cancelled caught (false: the work ended before the stop)
  double latency_s = 0.0;
};

/// Runs `work(stop)`, requests the stop `delay_s` after it starts, and measures the time from
/// the request to the Cancelled.
Latency measure(const std::function<void(const StopSource&)>& work, double delay_s) {
  StopSource stop;
  Clock::time_point requested{};
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
    requested = Clock::now();
    stop.request_stop();
  });
  Latency l;
  try {
    work(stop);
  } catch (const Cancelled&) {
    l.stopped = true;
  }
  const Clock::time_point end = Clock::now();
  stopper.join();
  l.latency_s = l.stopped ? seconds(requested, end) : 0.0;
  return l;
}

std::vector<double> delays_of(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stod(item));
  return out;
}

void row(const char* what, double delay_s, const Latency& l) {
  if (l.stopped) {
    std::printf("| %s | %.2f | %.1f |\n", what, delay_s, 1e3 * l.latency_s);
  } else {
    std::printf("| %s | %.2f | ended before the stop |\n", what, delay_s);
  }
}

/// Rows for `work` stopped after each of `delays`; returns the longest latency.
double rows(const char* what, const std::vector<double>& delays,
            const std::function<void(const StopSource&)>& work) {
  double worst_s = 0.0;
  for (double d : delays) {
    const Latency l = measure(work, d);
    row(what, d, l);
    worst_s = std::max(worst_s, l.latency_s);
  }
  return worst_s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_stop CL_FILE MESH_FILE [delays_s] [job points]\n");
    return 2;
  }
  const Toolpath toolpath = read_cl_file(argv[1]);
  const TriangleMesh mesh = read_mesh_file(argv[2]);
  Clock::time_point t0 = Clock::now();
  const Part part(mesh);
  const double build_s = seconds(t0, Clock::now());
  JobOptions options;
  options.part = &part;
  t0 = Clock::now();
  run_job(toolpath, default_machine(), options);
  const double job_s = seconds(t0, Clock::now());
  std::printf("%zu faces: Part built in %.2f s; run_job %.2f s (%zu operations)\n\n",
              mesh.faces.size(), build_s, job_s, toolpath.operations.size());
  std::vector<double> delays =
      argc > 3 ? delays_of(argv[3]) : std::vector<double>{0.0, 0.05, 0.1, 0.2, 0.4, 0.8, 1.2};
  // The job stopped at evenly spread moments of its whole run (its stages in turn).
  const int points = argc > 4 ? std::stoi(argv[4]) : 24;
  std::vector<double> job_delays;
  for (int k = 0; k < points; ++k) job_delays.push_back(job_s * (k + 0.5) / points);
  std::printf("| what is stopped | stop after, s | latency, ms |\n|---|---:|---:|\n");
  const double part_worst_s =
      rows("building the Part", delays, [&](const StopSource& s) { Part p(mesh, s); });
  const double job_worst_s = rows("run_job", job_delays, [&](const StopSource& s) {
    JobOptions o = options;
    o.stop = s;
    run_job(toolpath, default_machine(), o);
  });
  std::printf("\nlongest: building the Part %.1f ms, run_job %.1f ms\n", 1e3 * part_worst_s,
              1e3 * job_worst_s);
  std::printf("bench_stop %s %s\n", argv[1], argv[2]);
  return 0;
}
