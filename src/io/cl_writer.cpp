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

std::string format_new_cl(const std::vector<Operationd>& operations) {
  std::string out;
  char buf[256];
  for (const auto& op : operations) {
    out +=
        "TOOL PATH/" + op.name + ",TOOL," + (op.tool.name.empty() ? "TOOL" : op.tool.name) + "\n";
    std::snprintf(buf, sizeof buf, "TLDATA/MILL,%.4f,%.4f,%.4f,0.0000,0.0000\n",
                  op.tool.diameter_mm, op.tool.corner_radius_mm, op.tool.flute_length_mm);
    out += buf;
    if (op.tool.number > 0) out += "LOAD/TOOL," + std::to_string(op.tool.number) + "\n";
    if (op.spindle_rpm > 0.0) {
      std::snprintf(buf, sizeof buf, "SPINDL/RPM,%.1f,%s\n", op.spindle_rpm,
                    op.spindle_clockwise ? "CLW" : "CCLW");
      out += buf;
    }
    double feed = -1.0;
    for (const auto& p : op.points) {
      if (p.motion == Motion::Rapid) {
        out += "RAPID\n";
      } else if (p.feed_mm_per_min != feed && p.feed_mm_per_min > 0.0) {
        std::snprintf(buf, sizeof buf, "FEDRAT/MMPM,%.4f\n", p.feed_mm_per_min);
        out += buf;
        feed = p.feed_mm_per_min;
      }
      out += goto_line("GOTO", p, 1.0) + "\n";
    }
    out += "END-OF-PATH\n";
  }
  return out;
}

}  // namespace taxopt
