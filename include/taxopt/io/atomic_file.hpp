#pragma once
/// @file Atomic output: every file of a run is first written to a temporary file beside its
/// target, and only when all are written are they renamed into place, as one (commit). A failed run
/// leaves no partial file and never overwrites a good one. After remove_pending_on_signals (the CLI
/// calls it; a library never touches a process's signals on its own), a SIGINT, SIGTERM or SIGHUP
/// (whose handler is the default one) removes the pending temporary files before the process
/// ends by it.

#include <string>
#include <vector>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// A set of output files committed together.
class TAXOPT_API OutputTransaction {
 public:
  OutputTransaction() = default;
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  /// Removes every temporary file not yet committed.
  ~OutputTransaction();

  /// Writes `content` to a temporary file in the directory of `path` (flushed to disk).
  /// @throws InputError naming `path` when it cannot be written.
  void stage(const std::string& path, const std::string& content);

  /// Renames every staged file onto its target, as one: the old files are kept (hard links,
  /// else copies) until every rename is done, and a failed rename puts the ones before it back
  /// (the old file, or none where there was none), so the targets are all new or all as they
  /// were. A signal remove_pending_on_signals handles waits until then (SIGKILL or a power
  /// cut cannot: a `.name.taxopt-old-*` link may then remain beside a target).
  /// @throws InputError on failure, every target as it was.
  void commit();

  /// Removes every staged temporary file.
  void abort() noexcept;

  /// Installs, once per process, handlers of the signals whose default ends the process
  /// (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1/2, SIGALRM, SIGXFSZ, SIGXCPU, SIGVTALRM,
  /// SIGPROF) that remove every transaction's pending temporary files and end the process by
  /// the signal; a handler someone else installed (or SIG_IGN) is kept.
  static void remove_pending_on_signals();

 private:
  struct Staged {
    std::string temp;
    std::string target;
    int slot = -1;  // where the signal handler finds it
  };
  std::vector<Staged> staged_;
};

/// True when `a` and `b` name the same existing file, the same name in one folder reached by
/// two paths (a bind mount, a linked folder), or the same path once made absolute and resolved
/// (links, ".", "..") as far as it exists.
TAXOPT_API bool same_file(const std::string& a, const std::string& b);

/// Why an output file cannot be written at `path` ("" when it can): a folder, a missing
/// folder, a folder without write permission. Checked before any work is done.
TAXOPT_API std::string writable_output_problem(const std::string& path);

}  // namespace taxopt
