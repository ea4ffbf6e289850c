#include "cl/cl_writer.hpp"

#include <cstdio>
#include <stdexcept>

#include "taxopt/io/cl_file.hpp"
#include "util/progress.hpp"
#include "util/text.hpp"

namespace taxopt {
namespace {

bool same_point(const CLPointd& a, const CLPointd& b) {
  return (a.tip_mm - b.tip_mm).norm() <= 1e-9 && (a.axis - b.axis).norm() <= 1e-12;
}

/// Appends `v` as printf's "%.*f" writes it.
void append_number(std::string& out, double v, int decimals) {
  const detail::FixedText f = detail::fixed_text(v, decimals);
  out.append(f.text, f.size);
}

/// A GOTO in the file's units and in the frame its record was given in (MSYS), appended to
/// `out`: WORD/x,y,z,i,j,k with 6 decimals for the tip, 9 for the axis.
void append_goto(std::string& out, const char* word, const CLPointd& p, double mm_per_file_unit,
                 const ClFrame* frame = nullptr) {
  Vec3d tip = p.tip_mm, axis = p.axis;
  if (frame) {
    tip = frame->rotation * tip + frame->origin_mm;
    axis = frame->rotation * axis;
  }
  const Vec3d t = tip / mm_per_file_unit;
  out += word;
  out += '/';
  for (int c = 0; c < 3; ++c) {
    if (c > 0) out += ',';
    append_number(out, t[c], 6);
  }
  for (int c = 0; c < 3; ++c) {
    out += ',';
    append_number(out, axis[c], 9);
  }
}

}  // namespace

std::string format_cl(const Toolpath& original, const std::vector<Operationd>& operations) {
  return cl::format_cl(original, operations, nullptr);
}

std::string cl::format_cl(const Toolpath& original, const std::vector<Operationd>& operations,
                          const StopSource* stop) {
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
  std::string out = original.byte_order_mark ? "\xEF\xBB\xBF" : "";
  // A record's text with its line ends as the file's (a record may span lines).
  const auto emit = [&](const std::string& text) {
    std::size_t from = 0;
    for (std::size_t nl = text.find('\n'); nl != std::string::npos; nl = text.find('\n', from)) {
      out.append(text, from, nl - from);
      out += original.line_end;
      from = nl + 1;
    }
    out.append(text, from, std::string::npos);
    out += original.line_end;
  };
  // A record whose points changed is written as GOTOs; the records it owns (a NURBS's KNOT
  // and CNTRL) go with it.
  std::vector<char> changed(original.records.size(), 0);
  for (std::size_t k = 0; k < original.records.size(); ++k) {
    detail::look_at_stop(stop, k, detail::kPointStride);
    const auto& r = original.records[k];
    if (r.point_count == 0 || r.op < 0) continue;
    const auto& before = original.operations[static_cast<std::size_t>(r.op)].points;
    const auto& after = operations[static_cast<std::size_t>(r.op)].points;
    for (int j = 0; j < r.point_count && !changed[k]; ++j) {
      const auto i = static_cast<std::size_t>(r.first_point + j);
      changed[k] = !same_point(before[i], after[i]);
    }
  }
  for (std::size_t k = 0; k < original.records.size(); ++k) {
    detail::look_at_stop(stop, k, detail::kPointStride);
    const auto& r = original.records[k];
    if (r.owner >= 0 && changed[static_cast<std::size_t>(r.owner)]) continue;
    if (!changed[k]) {
      emit(r.text);
      continue;
    }
    const char* word = r.major == "FROM" ? "FROM" : "GOTO";
    const ClFrame* frame =
        r.frame >= 0 ? &original.frames[static_cast<std::size_t>(r.frame)] : nullptr;
    for (int j = 0; j < r.point_count; ++j) {
      append_goto(out, word,
                  operations[static_cast<std::size_t>(r.op)]
                      .points[static_cast<std::size_t>(r.first_point + j)],
                  scale, frame);
      out += original.line_end;
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
      append_goto(out, "GOTO", p, 1.0);
      out += "\n";
    }
    out += "END-OF-PATH\n";
  }
  return out;
}

}  // namespace taxopt
