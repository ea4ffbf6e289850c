#include "taxopt/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "taxopt/core/error.hpp"

namespace taxopt {

OutputTransaction::~OutputTransaction() { abort(); }

void OutputTransaction::stage(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, 0, "cannot write: is a directory");
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string templ = (dir / ("." + target.filename().string() + ".taxopt-XXXXXX")).string();
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  const int fd = ::mkstemp(buf.data());
  if (fd < 0) {
    throw InputError(path, 0, std::string("cannot write: ") + std::strerror(errno));
  }
  const std::string temp(buf.data());
  staged_.push_back({temp, path});
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

void OutputTransaction::commit() {
  for (std::size_t k = 0; k < staged_.size(); ++k) {
    if (std::rename(staged_[k].temp.c_str(), staged_[k].target.c_str()) != 0) {
      const int err = errno;
      staged_.erase(staged_.begin(), staged_.begin() + static_cast<long>(k));
      throw InputError(staged_.front().target, 0,
                       std::string("cannot write: ") + std::strerror(err));
    }
  }
  staged_.clear();
}

void OutputTransaction::abort() noexcept {
  for (const auto& s : staged_) std::remove(s.temp.c_str());
  staged_.clear();
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

}  // namespace taxopt
