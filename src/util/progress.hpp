#pragma once
/// @file Private helper of the compiled library (not installed): progress of one stage of a
/// run, reported through JobOptions::progress from any thread, never concurrently.

#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <string>

#include "taxopt/core/stop.hpp"

namespace taxopt::detail {

/// Every this many items a long loop of a part's build looks at the stop (a few ms of work).
constexpr std::size_t kStopStride = std::size_t{1} << 16;

/// Every this many points, blocks or lines a loop over a program looks at the stop (each a few
/// microseconds of work).
constexpr std::size_t kPointStride = 1024;

/// Looks at the stop, where one is given, at every `stride`-th item `i` of a loop: a stride
/// of a few milliseconds' work at most (JobOptions::stop is honoured within 100 ms).
inline void look_at_stop(const StopSource* stop, std::size_t i, std::size_t stride = kStopStride) {
  if (stop && i % stride == 0) stop->throw_if_stop_requested();
}

/// Counts the work items of a stage and reports each whole percent once, and the end. The
/// callback is the caller's code: what it throws stops the job (StopSource::request_stop with
/// that exception) instead of passing through the job's threads and destructors; advance()
/// and check() throw it, or Cancelled, once a stop is requested.
class StageProgress {
 public:
  using Callback = std::function<void(const std::string&, std::size_t, std::size_t)>;

  StageProgress(const Callback& callback, std::string stage, std::size_t total,
                const StopSource& stop)
      : callback_(callback), stage_(std::move(stage)), total_(total), stop_(stop) {
    check();
    report(0);
    check();
  }
  /// A watch: the stop looked at with every item, no progress reported (sweeps that run
  /// inside another stage's item).
  StageProgress(std::size_t total, const StopSource& stop)
      : StageProgress(no_report(), std::string(), total, stop) {}
  StageProgress(const StageProgress&) = delete;
  StageProgress& operator=(const StageProgress&) = delete;
  /// Reports the end (done = total) if the stage has not, unless it is being left by an
  /// exception or a stop.
  ~StageProgress() {
    if (std::uncaught_exceptions() == exceptions_ && !stop_.stop_requested()) report(total_);
  }

  /// `n` more items done (thread-safe); throws when the job is to stop.
  void advance(std::size_t n = 1) {
    report(done_ += n);
    check();
  }
  /// `n` more items done, without looking at the stop (for a destructor: it must not throw).
  void count(std::size_t n = 1) noexcept { report(done_ += n); }
  /// Throws the callback's exception, or Cancelled, when the job is to stop.
  void check() const { stop_.throw_if_stop_requested(); }

 private:
  /// Calls the callback for a new whole percent; never throws.
  void report(std::size_t done) noexcept {
    if (!callback_) return;
    done = done > total_ ? total_ : done;
    const long percent = total_ ? static_cast<long>(100 * done / total_) : 100;
    std::lock_guard<std::mutex> lock(mutex_);
    if (percent <= last_percent_ || ended_ || stop_.stop_requested()) return;
    last_percent_ = percent;
    ended_ = done == total_;
    try {
      callback_(stage_, done, total_);
    } catch (...) {
      stop_.request_stop(std::current_exception());
    }
  }

  static const Callback& no_report() {
    static const Callback none;
    return none;
  }

  const Callback& callback_;
  std::string stage_;
  std::size_t total_;
  const StopSource& stop_;
  int exceptions_ = std::uncaught_exceptions();
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  long last_percent_ = -1;
  bool ended_ = false;
};

}  // namespace taxopt::detail
