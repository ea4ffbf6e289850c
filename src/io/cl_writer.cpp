#include <cstdio>
#include <stdexcept>

#include "taxopt/io/cl_file.hpp"

namespace taxopt {
namespace {

bool same_point(const CLPointd& a, const CLPointd& b) {
  return (a.tip_mm - b.tip_mm).norm() <= 1e-9 && (a.axis - b.axis).norm() <= 1e-12;
}

std::string goto_line(const char* word, const CLPointd& p, double mm_per_file_unit) {
  const Vec3d t = p.tip_mm / mm_per_file_unit;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s/%.6f,%.6f,%.6f,%.9f,%.9f,%.9f", word, t.x(), t.y(), t.z(),
                p.axis.x(), p.axis.y(), p.axis.z());
  return buf;
}

}  // namespace

std::string format_cl(const Toolpath& original, const std::vector<Operationd>& operations) {
  if (operations.size() != original.operations.size()) {
    throw std::invalid_argument("format_cl: operations do not match the toolpath's");
  }
  for (std::size_t k = 0; k < operations.size(); ++k) {
    if (operations[k].points.size() != original.operations[k].points.size()) {
      throw std::invalid_argument("format_cl: operation " + std::to_string(k) +
                                  " has another number of points than the toolpath's");
    }
  }
  const double scale = mm_per_unit(original.units);
  std::string out;
  const auto emit = [&](const std::string& text) {
    for (char c : text) {
      if (c == '\n') {
        out += original.line_end;
      } else {
        out += c;
      }
    }
    out += original.line_end;
  };
  for (const auto& r : original.records) {
    if (r.point_count == 0 || r.op < 0) {
      emit(r.text);
      continue;
    }
    const auto& before = original.operations[static_cast<std::size_t>(r.op)].points;
    const auto& after = operations[static_cast<std::size_t>(r.op)].points;
    bool changed = false;
    for (int k = 0; k < r.point_count; ++k) {
      const auto i = static_cast<std::size_t>(r.first_point + k);
      changed = changed || !same_point(before[i], after[i]);
    }
    if (!changed) {
      emit(r.text);
      continue;
    }
    const char* word = r.major == "FROM" ? "FROM" : "GOTO";
    for (int k = 0; k < r.point_count; ++k) {
      emit(goto_line(word, after[static_cast<std::size_t>(r.first_point + k)], scale));
    }
  }
  if (!original.final_line_end && !out.empty()) {
    out.resize(out.size() - original.line_end.size());
  }
  return out;
}

}  // namespace taxopt
