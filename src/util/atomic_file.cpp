#include "taxopt/io/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>

#include "taxopt/core/error.hpp"

namespace taxopt {
namespace {

// Temporary files not yet renamed into place, for the SIGINT/SIGTERM handler: it may only call
// async-signal-safe functions, so the paths live in fixed slots (a slot is published by its
// `used` flag after its path is written, and withdrawn before it is reused).
constexpr std::size_t kSlots = 64;
struct PendingSlot {
  std::atomic<bool> used{false};
  char path[4096] = {};
};
std::array<PendingSlot, kSlots> g_pending;
std::mutex g_pending_mutex;

// While a transaction renames its files into place (or back), a signal is held until the set
// is whole, new or old: the handler records it and returns, and the commit raises it after.
std::atomic<bool> g_committing{false};
std::atomic<int> g_deferred_signal{0};

// Internal linkage: a handler of this file's, not a symbol of the library.
extern "C" {
static void remove_pending_and_reraise(int sig) {
  if (g_committing.load()) {
    g_deferred_signal.store(sig);
    return;
  }
  for (auto& s : g_pending) {
    if (s.used.load()) ::unlink(s.path);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}
}  // extern "C"

}  // namespace

void OutputTransaction::remove_pending_on_signals() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Every signal whose default ends the process (SIGKILL and SIGSTOP cannot be caught).
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGXFSZ, SIGXCPU,
                    SIGVTALRM, SIGPROF}) {
      struct sigaction sa {};
      sa.sa_handler = remove_pending_and_reraise;
      sigemptyset(&sa.sa_mask);
      struct sigaction old {};
      // Keep a handler someone else installed (or SIG_IGN): only the default is replaced.
      if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_DFL) {
        ::sigaction(sig, &sa, nullptr);
      }
    }
  });
}

namespace {

/// Publishes a temporary path for the signal handler; -1 when every slot is taken (the file
/// is then only removed by the transaction itself).
int publish_pending(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_pending_mutex);
  if (path.size() >= sizeof(PendingSlot::path)) return -1;
  for (std::size_t k = 0; k < kSlots; ++k) {
    if (!g_pending[k].used.load()) {
      std::memcpy(g_pending[k].path, path.c_str(), path.size() + 1);
      g_pending[k].used.store(true);
      return static_cast<int>(k);
    }
  }
  return -1;
}

void withdraw_pending(int slot) {
  if (slot < 0) return;
  std::lock_guard<std::mutex> lock(g_pending_mutex);
  g_pending[static_cast<std::size_t>(slot)].used.store(false);
}

}  // namespace

OutputTransaction::~OutputTransaction() { abort(); }

void OutputTransaction::stage(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, 0, "cannot write: is a directory");
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  // The temporary file's name is chosen and published to the signal handler before the file
  // is created (O_EXCL), so that a signal taken on any thread, at any moment, finds it: a
  // handler that unlinks a name not yet created does no harm. This thread blocks the signals
  // meanwhile so that it does not run the handler between publishing and recording the file.
  sigset_t block, saved;
  sigemptyset(&block);
  sigaddset(&block, SIGINT);
  sigaddset(&block, SIGTERM);
  sigaddset(&block, SIGHUP);
  static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  std::random_device random;
  int fd = -1, open_errno = 0;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    std::string name = "." + target.filename().string() + ".taxopt-";
    for (int k = 0; k < 12; ++k) name += kChars[random() % (sizeof(kChars) - 1)];
    const std::string temp = (dir / name).string();
    ::pthread_sigmask(SIG_BLOCK, &block, &saved);
    const int slot = publish_pending(temp);
    fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    open_errno = errno;
    if (fd >= 0) {
      staged_.push_back({temp, path, slot});
    } else {
      withdraw_pending(slot);
    }
    ::pthread_sigmask(SIG_SETMASK, &saved, nullptr);
    if (fd < 0 && open_errno != EEXIST) break;
  }
  if (fd < 0) {
    throw InputError(path, 0, std::string("cannot write: ") + std::strerror(open_errno));
  }
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path, 0, std::string("cannot write: ") + std::strerror(err));
    }
    done += static_cast<std::size_t>(n);
  }
  // Files are created 0600 by mkstemp; give them the usual permissions (umask applies).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, static_cast<mode_t>(0666 & ~mask));
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    throw InputError(path, 0, std::string("cannot write: ") + std::strerror(errno));
  }
}

namespace {

/// A hard link to `target` beside it (its old content, for a rollback); "" when there is no
/// target. @throws InputError when the old file can be neither linked nor copied.
std::string keep_old(const std::string& target) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(target, ec))) return "";
  const fs::path t(target);
  const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
  std::random_device random;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string old =
        (dir / ("." + t.filename().string() + ".taxopt-old-" + std::to_string(random()))).string();
    if (::link(target.c_str(), old.c_str()) == 0) return old;
    if (errno == EEXIST) continue;
    // No hard links here (a FAT or network share): a copy keeps the content as well.
    if (fs::copy_file(target, old, fs::copy_options::none, ec)) return old;
    break;
  }
  throw InputError(target, 0,
                   "cannot keep the old file for the outputs' rollback (every output of the run "
                   "left as it was)");
}

}  // namespace

void OutputTransaction::commit() {
  // Every output is new or every one is as it was: the old files are kept as links, the new
  // ones renamed in, and on a failure the ones already renamed are put back. Signals wait.
  // From the first kept link on: a signal in between would leave the links behind.
  g_committing.store(true);
  std::vector<std::string> old;
  try {
    for (const Staged& s : staged_) old.push_back(keep_old(s.target));
  } catch (...) {
    for (const std::string& o : old) {
      if (!o.empty()) ::unlink(o.c_str());
    }
    g_committing.store(false);
    if (const int sig = g_deferred_signal.exchange(0)) std::raise(sig);
    throw;
  }
  std::size_t done = 0;
  int err = 0;
  for (; done < staged_.size(); ++done) {
    if (std::rename(staged_[done].temp.c_str(), staged_[done].target.c_str()) != 0) {
      err = errno;
      break;
    }
  }
  if (err != 0) {
    for (std::size_t j = 0; j < done; ++j) {
      // The new file back out: the old one over it, or none where there was none.
      if (old[j].empty()) {
        ::unlink(staged_[j].target.c_str());
      } else {
        std::rename(old[j].c_str(), staged_[j].target.c_str());
        old[j].clear();
      }
    }
  }
  for (const std::string& o : old) {
    if (!o.empty()) ::unlink(o.c_str());
  }
  for (std::size_t j = 0; j < done; ++j) withdraw_pending(staged_[j].slot);
  const std::string failed = err != 0 ? staged_[done].target : std::string();
  staged_.erase(staged_.begin(), staged_.begin() + static_cast<long>(done));
  g_committing.store(false);
  if (const int sig = g_deferred_signal.exchange(0)) std::raise(sig);
  if (err != 0) {
    throw InputError(failed, 0,
                     std::string("cannot write: ") + std::strerror(err) +
                         " (every output of the run left as it was)");
  }
}

void OutputTransaction::abort() noexcept {
  for (const auto& s : staged_) {
    std::remove(s.temp.c_str());
    withdraw_pending(s.slot);
  }
  staged_.clear();
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  // One folder under two names (a bind mount, a linked folder): the same name in it is one
  // file ("a/x.nc" and "b/x.nc" with b a bind mount of a: the report replaced the program).
  const fs::path pa = fs::absolute(a, ec), pb = fs::absolute(b, ec);
  if (pa.filename() == pb.filename() && fs::exists(pa.parent_path(), ec) &&
      fs::exists(pb.parent_path(), ec) && fs::equivalent(pa.parent_path(), pb.parent_path(), ec)) {
    return true;
  }
  // Not both there yet: compare absolute paths with links and "." and ".." resolved as far as
  // the folders exist ("same.out" and "./same.out" are one file).
  const auto resolved = [](const std::string& p) {
    std::error_code e;
    const fs::path abs = fs::absolute(p, e);
    const fs::path r = fs::weakly_canonical(abs, e);
    return (e ? abs : r).lexically_normal();
  };
  return resolved(a) == resolved(b);
}

std::string writable_output_problem(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) return "is a folder";
  // Renaming over a link replaces the link, not its target (`--gcode /dev/stdout` replaced
  // the system's /dev/stdout link with a regular file): name the target instead.
  if (fs::is_symlink(fs::symlink_status(path, ec))) {
    return "is a symbolic link (the output would replace the link, not write its target; name "
           "the target)";
  }
  const fs::file_status st = fs::status(path, ec);
  if (fs::exists(st)) {
    // The output replaces the file by renaming over it: a device, FIFO or socket would be
    // replaced by a regular file, and a file whose mode forbids writing would be written.
    if (!fs::is_regular_file(st)) return "is not a regular file (a device, FIFO or socket)";
    if ((st.permissions() & (fs::perms::owner_write | fs::perms::group_write |
                             fs::perms::others_write)) == fs::perms::none) {
      return "is read-only (its mode has no write bit)";
    }
  }
  const fs::path target = fs::absolute(path, ec);
  const fs::path dir = target.parent_path();
  if (!fs::exists(dir, ec)) return "its folder " + dir.string() + " does not exist";
  if (!fs::is_directory(dir, ec)) return dir.string() + " is not a folder";
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    return "cannot write in its folder " + dir.string() + ": " + std::strerror(errno);
  }
  // What the write will do, tried: a temporary file of the same name's length in the same
  // folder (a 300-character name, or /sys where root passes access(), failed only after the
  // whole run).
  std::string probe = (dir / ("." + target.filename().string() + ".taxopt-XXXXXXXXXXXX")).string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) return std::strerror(errno);
  ::close(fd);
  ::unlink(probe.c_str());
  return "";
}

}  // namespace taxopt
