#pragma once
/// @file Stopping a running job from its caller: JobOptions::stop and the Cancelled outcome.

#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// A job its caller stopped (JobOptions::stop): run_job and plan_axes throw it and return no
/// result, so nothing is written from them.
class TAXOPT_API Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("the job was stopped by its caller (JobOptions::stop)") {}
};

/// A caller's handle to stop a running job from any thread: copies share one flag. The job
/// checks it between its stages and as its long stages advance (inside their parallel loops)
/// and ends with Cancelled -- or with the exception a progress callback threw, which stops
/// the job the same way (the callback runs on the job's threads, where it cannot be thrown
/// through).
class TAXOPT_API StopSource {
 public:
  StopSource() : state_(std::make_shared<State>()) {}

  /// Asks the job to stop; `reason`, when given, is what the job throws instead of Cancelled
  /// (the first reason given is kept).
  void request_stop(std::exception_ptr reason = nullptr) const noexcept {
    if (reason) {
      std::lock_guard<std::mutex> lock(state_->mutex);
      if (!state_->reason) state_->reason = reason;
    }
    state_->requested.store(true);
  }
  bool stop_requested() const noexcept { return state_->requested.load(); }
  /// Throws the reason given, else Cancelled, when a stop was requested.
  void throw_if_stop_requested() const {
    if (!stop_requested()) return;
    std::exception_ptr reason;
    {
      std::lock_guard<std::mutex> lock(state_->mutex);
      reason = state_->reason;
    }
    if (reason) std::rethrow_exception(reason);
    throw Cancelled();
  }

 private:
  struct State {
    std::atomic<bool> requested{false};
    std::mutex mutex;
    std::exception_ptr reason;
  };
  std::shared_ptr<State> state_;
};

}  // namespace taxopt
