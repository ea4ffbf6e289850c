#pragma once
/// @file Private helper of the compiled library (not installed): progress of one stage of a
/// run, reported through JobOptions::progress from any thread, never concurrently.

#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string>

namespace taxopt::detail {

/// Counts the work items of a stage and reports each whole percent once, and the end.
class StageProgress {
 public:
  using Callback = std::function<void(const std::string&, std::size_t, std::size_t)>;

  StageProgress(const Callback& callback, std::string stage, std::size_t total)
      : callback_(callback), stage_(std::move(stage)), total_(total) {
    report(0);
  }
  StageProgress(const StageProgress&) = delete;
  StageProgress& operator=(const StageProgress&) = delete;
  /// Reports the end (done = total) if the stage has not.
  ~StageProgress() { report(total_); }

  /// `n` more items done (thread-safe).
  void advance(std::size_t n = 1) { report(done_ += n); }

  /// One item done when it goes out of scope, whichever way the work of the item ends.
  class Step {
   public:
    explicit Step(StageProgress& progress) : progress_(progress) {}
    Step(const Step&) = delete;
    Step& operator=(const Step&) = delete;
    ~Step() { progress_.advance(); }

   private:
    StageProgress& progress_;
  };

 private:
  void report(std::size_t done) {
    if (!callback_) return;
    done = done > total_ ? total_ : done;
    const long percent = total_ ? static_cast<long>(100 * done / total_) : 100;
    std::lock_guard<std::mutex> lock(mutex_);
    if (percent <= last_percent_ || ended_) return;
    last_percent_ = percent;
    ended_ = done == total_;
    callback_(stage_, done, total_);
  }

  const Callback& callback_;
  std::string stage_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  long last_percent_ = -1;
  bool ended_ = false;
};

}  // namespace taxopt::detail
