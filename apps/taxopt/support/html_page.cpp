// The HTML page of a run (html_page.hpp): the data as JSON in the page, the libraries embedded,
// the page's own style, body and script in html_page.css, html_page_body.html and html_page.js.
#include "support/html_page.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "html_page_script.hpp"
#include "taxopt/core/error.hpp"
#include "util/input_file.hpp"

namespace taxopt {

namespace {

std::string read_asset(const std::string& dir, const std::string& rel, const char* package) {
  const std::string path = dir + "/" + rel;
  const std::string missing =
      std::string("cannot read this file, which the HTML page embeds: install ") + package +
      " (scripts/setup.sh does)";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, missing);
  // A regular file of a library's size: a FIFO there blocked --html forever, /dev/zero read
  // until memory ran out (issue 63.11).
  constexpr std::uintmax_t kMostAssetBytes = 64u << 20;
  const std::string bytes = detail::read_input_file(
      path, kMostAssetBytes, "a JavaScript library", "this file, which the HTML page embeds",
      "larger than 64 MB: no JavaScript library the HTML page embeds is");
  if (bytes.empty()) throw InputError(path, 0, missing);
  return bytes;
}

/// Data placed inside a <script> element: every '<' as "\u003c" (only JSON strings hold one), so
/// that no "</script" ends the element early and no "<!--" opens the parser's escaped state.
std::string json_inside_script(const std::string& json_text) {
  std::string out;
  out.reserve(json_text.size());
  for (char c : json_text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

/// A library placed inside a <script> or <style> element as read: checked that it holds
/// nothing that would end the element early ("</script", "</style") or open the HTML parser's
/// escaped state ("<!--"); Debian's files hold none (a "</div" in a string is harmless).
const std::string& library_inside_element(const std::string& text, const char* what) {
  std::string lower(text.size(), ' ');
  std::transform(text.begin(), text.end(), lower.begin(), [](char c) {
    return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  });
  for (const char* bad : {"</script", "</style", "<!--"}) {
    if (lower.find(bad) != std::string::npos) {
      throw InputError(what, 0,
                       std::string("the library holds \"") + bad +
                           "\", which would end its element in the HTML page early");
    }
  }
  return text;
}

std::string escape_html(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// x rounded to `decimals` (the page shows 3; the file stays small), never -0.
double rounded(double x, int decimals = 3) {
  if (!std::isfinite(x)) return 0.0;
  const double scale = std::pow(10.0, decimals);
  const double r = std::round(x * scale) / scale;
  return r == 0.0 ? 0.0 : r;
}

std::string fixed(double x, int decimals) {
  std::ostringstream os;
  os.precision(decimals);
  os << std::fixed << rounded(x, decimals);
  return os.str();
}

nlohmann::json vec_json(const Vec3d& v, int decimals) {
  return nlohmann::json::array(
      {rounded(v.x(), decimals), rounded(v.y(), decimals), rounded(v.z(), decimals)});
}

/// The rows an operation's plots show: every k-th and, within each stride, the largest omega
/// and a before and after; sorted.
std::vector<std::size_t> plotted_rows(const std::vector<PointRow>& rows, std::size_t stride) {
  std::vector<std::size_t> keep;
  for (std::size_t start = 0; start < rows.size(); start += stride) {
    const std::size_t end = std::min(rows.size(), start + stride);
    keep.push_back(start);
    std::array<std::size_t, 4> best{start, start, start, start};
    for (std::size_t i = start; i < end; ++i) {
      const PointRow& r = rows[i];
      if (r.omega_deg_s > rows[best[0]].omega_deg_s) best[0] = i;
      if (r.omega_before_deg_s > rows[best[1]].omega_before_deg_s) best[1] = i;
      if (r.accel_deg_s2 > rows[best[2]].accel_deg_s2) best[2] = i;
      if (r.accel_before_deg_s2 > rows[best[3]].accel_before_deg_s2) best[3] = i;
    }
    keep.insert(keep.end(), best.begin(), best.end());
  }
  if (!rows.empty()) keep.push_back(rows.size() - 1);
  std::sort(keep.begin(), keep.end());
  keep.erase(std::unique(keep.begin(), keep.end()), keep.end());
  return keep;
}

nlohmann::json range_json(const RotaryAxis<double>& axis) {
  if (axis.continuous || !std::isfinite(axis.min_rad) || !std::isfinite(axis.max_rad)) {
    return nullptr;
  }
  return nlohmann::json::array(
      {rounded(rad_to_deg(axis.min_rad)), rounded(rad_to_deg(axis.max_rad))});
}

nlohmann::json limit_json(const JointLimit& l) {
  nlohmann::json j;
  j["velocity_deg_s"] = l.max_velocity_per_s > 0.0 ? nlohmann::json(l.max_velocity_per_s) : nullptr;
  j["accel_deg_s2"] = l.max_accel_per_s2 > 0.0 ? nlohmann::json(l.max_accel_per_s2) : nullptr;
  return j;
}

/// The axis nearest its machine limit as shares of the limit (the CLI's table says the same),
/// else the paper's combined peak a.
std::string worst_axis_cell(const SummaryRow& r) {
  if (!r.worst_axis) {
    return "(combined a) " + fixed(r.peak_accel_deg_s2.before, 1) + " &rarr; " +
           fixed(r.peak_accel_deg_s2.after, 1);
  }
  const AxisShare& w = *r.worst_axis;
  return std::string(1, w.axis) + (w.rate == "omega" ? " &omega; " : " a ") +
         fixed(100.0 * w.before, 0) + " % &rarr; " + fixed(100.0 * w.after, 0) + " %";
}

std::string summary_table(const JobResult& result) {
  std::ostringstream t;
  // Per rotary axis: one combined figure hid a tilt axis whose peak rose while C's fell.
  const std::string tilt(1, result.tilt_letter);
  t << "<table class=\"summary\"><thead><tr><th>operation</th><th>points</th>"
       "<th>peak &omega; "
    << tilt
    << " deg/s<br>before &rarr; after</th><th>peak &omega; C deg/s<br>before &rarr; after</th>"
    << "<th>peak a " << tilt
    << " deg/s&sup2;<br>before &rarr; after</th><th>peak a C deg/s&sup2;<br>before &rarr; "
       "after</th>"
       "<th>nearest its limit<br>before &rarr; after</th>"
       "<th>RMS a deg/s&sup2;<br>before &rarr; after</th>"
       "<th>C flips<br>before &rarr; after</th>"
       "<th>colliding points<br>before &rarr; after</th><th>colliding moves</th>"
       "<th>input axes kept</th><th>cycle s<br>before &rarr; after</th></tr></thead><tbody>";
  const auto pair = [](const BeforeAfter<double>& v, int d) {
    return fixed(v.before, d) + " &rarr; " + fixed(v.after, d);
  };
  for (const SummaryRow& r : summary_rows(result)) {
    t << "<tr><td>" << escape_html(r.operation) << "</td><td>" << r.points << "</td><td>"
      << pair(r.peak_omega_tilt_deg_s, 2) << "</td><td>" << pair(r.peak_omega_c_deg_s, 2)
      << "</td><td>" << pair(r.peak_accel_tilt_deg_s2, 1) << "</td><td>"
      << pair(r.peak_accel_c_deg_s2, 1) << "</td><td>" << worst_axis_cell(r) << "</td><td>"
      << pair(r.rms_accel_deg_s2, 1) << "</td><td>" << r.c_jumps.before << " &rarr; "
      << r.c_jumps.after << "</td><td>";
    if (!r.colliding_points) {
      t << "<span class=\"unchecked\">NOT CHECKED</span></td><td>"
           "<span class=\"unchecked\">NOT CHECKED</span>";
    } else {
      t << r.colliding_points->before << " &rarr; " << r.colliding_points->after << "</td><td>"
        << (r.colliding_moves ? std::to_string(*r.colliding_moves) : std::string("-"));
    }
    t << "</td><td>" << (r.input_axes_kept ? std::to_string(*r.input_axes_kept) : "-")
      << "</td><td>" << pair(r.cycle_time_s, 2) << "</td></tr>";
  }
  t << "</tbody></table>";
  return t.str();
}

}  // namespace

HtmlAssets load_html_assets(const std::string& javascript_dir) {
  HtmlAssets a;
  a.three_js = read_asset(javascript_dir, "three/three.min.js", "libjs-three");
  a.orbit_controls_js =
      read_asset(javascript_dir, "three/examples/js/controls/OrbitControls.js", "libjs-three");
  a.dygraph_js = read_asset(javascript_dir, "dygraphs/dygraph.min.js", "libjs-dygraphs");
  a.dygraph_css = read_asset(javascript_dir, "dygraphs/dygraph.min.css", "libjs-dygraphs");
  return a;
}

TriangleMesh decimate_mesh(const TriangleMesh& mesh, std::size_t max_triangles, double* cell_mm) {
  if (cell_mm) *cell_mm = 0.0;
  if (mesh.faces.size() <= max_triangles || mesh.vertices.empty()) return mesh;
  Vec3d lo = mesh.vertices.front(), hi = lo;
  for (const Vec3d& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double diagonal = std::max((hi - lo).norm(), 1e-9);
  // A start where the grid has about as many cells across a face of the box as the budget's
  // square root; coarser by a quarter until within the budget.
  double cell = diagonal / std::sqrt(static_cast<double>(std::max<std::size_t>(max_triangles, 1)));
  for (int attempt = 0; attempt < 200; ++attempt, cell *= 1.25) {
    std::map<std::array<long, 3>, int> cluster_of_key;
    std::vector<int> cluster(mesh.vertices.size());
    std::vector<Vec3d> sum;
    std::vector<int> count;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Vec3d g = (mesh.vertices[i] - lo) / cell;
      const std::array<long, 3> key{static_cast<long>(std::floor(g.x())),
                                    static_cast<long>(std::floor(g.y())),
                                    static_cast<long>(std::floor(g.z()))};
      const auto [it, added] = cluster_of_key.emplace(key, static_cast<int>(sum.size()));
      if (added) {
        sum.push_back(Vec3d::Zero());
        count.push_back(0);
      }
      cluster[i] = it->second;
      sum[static_cast<std::size_t>(it->second)] += mesh.vertices[i];
      ++count[static_cast<std::size_t>(it->second)];
    }
    TriangleMesh out;
    for (std::size_t c = 0; c < sum.size(); ++c) out.vertices.push_back(sum[c] / count[c]);
    std::set<std::array<int, 3>> seen;
    for (const auto& f : mesh.faces) {
      std::array<int, 3> g{cluster[static_cast<std::size_t>(f[0])],
                           cluster[static_cast<std::size_t>(f[1])],
                           cluster[static_cast<std::size_t>(f[2])]};
      if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;
      std::array<int, 3> sorted = g;
      std::sort(sorted.begin(), sorted.end());
      if (!seen.insert(sorted).second) continue;
      out.faces.push_back(g);
    }
    if (out.faces.size() <= max_triangles) {
      if (cell_mm) *cell_mm = cell;
      return out;
    }
  }
  return TriangleMesh{};  // never: at 200 steps the cell is far larger than the part
}

namespace {

using nlohmann::json;

/// The part, decimated to the budget; null without one.
json mesh_json(const TriangleMesh* part_mm, const HtmlBudget& budget) {
  json data;
  if (part_mm && !part_mm->faces.empty()) {
    double cell = 0.0;
    const TriangleMesh shown = decimate_mesh(*part_mm, budget.max_triangles, &cell);
    json v = json::array(), f = json::array();
    for (const Vec3d& p : shown.vertices) {
      v.push_back(rounded(p.x()));
      v.push_back(rounded(p.y()));
      v.push_back(rounded(p.z()));
    }
    for (const auto& t : shown.faces) {
      f.push_back(t[0]);
      f.push_back(t[1]);
      f.push_back(t[2]);
    }
    data["mesh"] = {{"vertices", std::move(v)},
                    {"faces", std::move(f)},
                    {"triangles_in", part_mm->faces.size()},
                    {"triangles_shown", shown.faces.size()},
                    {"cell_mm", rounded(cell)}};
  } else {
    data["mesh"] = nullptr;
  }

  return data["mesh"];
}

/// The plots' series of the rows `shown` (plotted_rows) into `o`: index, CL line, arc length,
/// the rotary angles, rates and feeds before and after, the pass and the tip's path.
void add_point_series(const std::vector<PointRow>& rows, const std::vector<std::size_t>& shown,
                      json& o) {
  json idx = json::array(), line = json::array(), arc = json::array(), ab = json::array(),
       aa = json::array(), cb = json::array(), ca = json::array(), wb = json::array(),
       wa = json::array(), gb = json::array(), ga = json::array(), fb = json::array(),
       fa = json::array(), path = json::array(), pass = json::array();
  std::size_t pass_number = 0;
  std::size_t at = 0;
  // The plots' x: the rows' arc length over the passes (the paper's L), carried over the
  // points outside them (rapids), so that it never runs back.
  double arc_mm = 0.0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const PointRow& p = rows[i];
    arc_mm = std::max(arc_mm, p.arc_mm);
    if (i > 0 && !p.feed_mm_min) ++pass_number;  // a rapid (or a move the schedule skips)
    if (at >= shown.size() || shown[at] != i) continue;
    ++at;
    idx.push_back(i);
    line.push_back(p.line);
    arc.push_back(rounded(arc_mm));
    ab.push_back(rounded(p.tilt_axis_before_deg));
    aa.push_back(rounded(p.tilt_axis_deg));
    cb.push_back(rounded(p.c_before_deg));
    ca.push_back(rounded(p.c_deg));
    wb.push_back(rounded(p.omega_before_deg_s));
    wa.push_back(rounded(p.omega_deg_s));
    gb.push_back(rounded(p.accel_before_deg_s2));
    ga.push_back(rounded(p.accel_deg_s2));
    fb.push_back(p.feed_before_mm_min ? json(rounded(*p.feed_before_mm_min, 1)) : json(nullptr));
    fa.push_back(p.feed_mm_min ? json(rounded(*p.feed_mm_min, 1)) : json(nullptr));
    pass.push_back(pass_number);
    path.push_back(rounded(p.tip_mm.x()));
    path.push_back(rounded(p.tip_mm.y()));
    path.push_back(rounded(p.tip_mm.z()));
  }
  o["idx"] = std::move(idx);
  o["line"] = std::move(line);
  o["arc_mm"] = std::move(arc);
  o["tilt_before"] = std::move(ab);
  o["tilt_after"] = std::move(aa);
  o["c_before"] = std::move(cb);
  o["c_after"] = std::move(ca);
  o["omega_before"] = std::move(wb);
  o["omega_after"] = std::move(wa);
  o["accel_before"] = std::move(gb);
  o["accel_after"] = std::move(ga);
  o["feed_before"] = std::move(fb);
  o["feed_after"] = std::move(fa);
  o["pass"] = std::move(pass);
  o["path"] = std::move(path);
}

/// The tool axes, before and after, at every `axes_every`-th point: index, tip, axis before,
/// axis after, the synthetic a before and after.
json tool_axes_json(const std::vector<PointRow>& rows, const Machine& machine,
                    std::size_t axes_every) {
  json axes = json::array();
  for (std::size_t i = 0; i < rows.size(); i += axes_every) {
    const PointRow& p = rows[i];
    const Vec3d before = machine.rotary.forward(
        Posed{deg_to_rad(p.tilt_axis_before_deg), deg_to_rad(p.c_before_deg)});
    axes.push_back({i, vec_json(p.tip_mm, 3), vec_json(before, 4), vec_json(p.axis, 4),
                    rounded(p.accel_before_deg_s2), rounded(p.accel_deg_s2)});
  }
  return axes;
}

/// An operation's series for the plots (every `plot_stride`-th row kept by plotted_rows) and
/// its tool axes before and after at every `axes_every`-th point.
json operation_series_json(const OperationResult& r, const Machine& machine,
                           std::size_t plot_stride, std::size_t axes_every,
                           std::size_t& plotted_total) {
  json o;
  o["name"] = r.name;
  o["points"] = r.rows.size();
  // The page's script reads -1 as "not checked" (with `checked` false).
  o["checked"] = r.colliding_after.has_value();
  o["colliding_after"] = r.colliding_after.value_or(-1);
  o["colliding_moves"] = r.verification.colliding_moves.value_or(-1);
  o["peaks"] = {{"omega_before", r.before.max_omega_deg_s},
                {"omega_after", r.after.max_omega_deg_s},
                {"accel_before", r.before.max_accel_deg_s2},
                {"accel_after", r.after.max_accel_deg_s2}};
  o["programmed_feed_mm_min"] = r.feed_mm_min;
  const std::vector<std::size_t> shown = plotted_rows(r.rows, plot_stride);
  plotted_total += shown.size();
  add_point_series(r.rows, shown, o);
  json keys = json::array();
  for (const PointRow& p : r.rows) {
    if (p.key) keys.push_back(rounded(p.arc_mm));
  }
  o["key_arc_mm"] = std::move(keys);
  o["axes"] = tool_axes_json(r.rows, machine, axes_every);
  return o;
}

/// The points where a check fired (not_checked is the operation's, shown on the path and in
/// the header, not a marker at every point), up to the budget; counted all.
void add_markers(const OperationResult& r, std::size_t k, const Machine& machine,
                 const HtmlBudget& budget, json& markers, std::size_t& marker_total) {
  const std::uint32_t not_checked = static_cast<std::uint32_t>(PointMark::NotChecked);
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    const PointRow& p = r.rows[i];
    const std::uint32_t m = p.marks & ~not_checked;
    if (m == 0) continue;
    ++marker_total;
    if (markers.size() >= budget.max_markers) continue;
    const Vec3d before = machine.rotary.forward(
        Posed{deg_to_rad(p.tilt_axis_before_deg), deg_to_rad(p.c_before_deg)});
    markers.push_back({{"op", k},
                       {"i", i},
                       {"line", p.line},
                       {"marks", point_marks_text(m)},
                       {"tip", vec_json(p.tip_mm, 3)},
                       {"arc_mm", rounded(p.arc_mm)},
                       {"tilt_before", rounded(p.tilt_axis_before_deg)},
                       {"c_before", rounded(p.c_before_deg)},
                       {"tilt_after", rounded(p.tilt_axis_deg)},
                       {"c_after", rounded(p.c_deg)},
                       {"axis_before", vec_json(before, 4)},
                       {"axis_after", vec_json(p.axis, 4)}});
  }
}

json findings_json(const JobResult& result) {
  json findings = json::array();
  for (const Finding& f : result.findings) {
    findings.push_back({{"code", to_string(f.code)},
                        {"severity", to_string(f.severity)},
                        {"op", f.operation ? json(*f.operation) : json(nullptr)},
                        {"line", f.line},
                        {"message", f.message}});
  }
  return findings;
}

/// The page's header: the run, the verdict and what was found, readable without scripts.
void write_header(std::ostringstream& page, const JobResult& result, const Toolpath& toolpath,
                  const Machine& machine, const JobOptions& options, const RunInfo& run,
                  const HtmlAssets& assets) {
  page << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
       << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
       << "<title>taxopt: " << escape_html(toolpath.source) << "</title>\n"
       << "<style>" << library_inside_element(assets.dygraph_css, "dygraph.min.css") << "</style>\n"
       << "<style>" << kHtmlPageCss << "</style>\n</head><body>\n";
  page << "<header><h1>taxopt &mdash; " << escape_html(toolpath.source)
       << "</h1>\n<dl class=\"run\">"
       << "<dt>command</dt><dd><code>" << escape_html(run.command_line) << "</code></dd>"
       << "<dt>started</dt><dd>" << escape_html(run.started_utc) << "</dd>"
       << "<dt>machine</dt><dd>" << escape_html(machine.name)
       << (run.machine_file.empty() ? std::string(" (built in)")
                                    : " (" + escape_html(run.machine_file) + ")")
       << "</dd><dt>method</dt><dd>" << to_string(options.method) << "</dd>"
       << "<dt>part</dt><dd>"
       << (run.part_file.empty() ? std::string("none") : escape_html(run.part_file)) << "</dd>"
       << "<dt>verdict</dt><dd class=\"" << (result.ok() ? "ok" : "problem") << "\">"
       << (result.ok()
               ? "no problem found"
               : std::to_string(result.problems.size()) + " problems: the G-code is not to be used")
       << "</dd></dl>\n";
  if (!result.safety_warnings.empty() || !result.problems.empty() || !result.warnings.empty()) {
    page << "<ul class=\"findings\">";
    for (const auto& s : result.problems)
      page << "<li class=\"problem\">" << escape_html(s) << "</li>";
    for (const auto& s : result.safety_warnings) {
      page << "<li class=\"unchecked\">NOT CHECKED: " << escape_html(s) << "</li>";
    }
    for (const auto& s : result.warnings)
      page << "<li class=\"warning\">" << escape_html(s) << "</li>";
    page << "</ul>\n";
  }
}

}  // namespace

std::string html_page(const JobResult& result, const Toolpath& toolpath, const Machine& machine,
                      const JobOptions& options, const RunInfo& run, const TriangleMesh* part_mm,
                      const HtmlAssets& assets, const HtmlBudget& budget) {
  json data;
  data["source"] = toolpath.source;
  data["method"] = to_string(options.method);
  data["tilt"] = std::string(1, result.tilt_letter);
  data["collision_checked"] = result.collision_checked;
  const JointLimits limits = effective_limits(machine);
  data["machine"] = {{"name", machine.name},
                     {"tilt_range_deg", range_json(machine.rotary.tilt)},
                     {"c_range_deg", range_json(machine.rotary.c)},
                     {"tilt_limits", limit_json(limits[3])},
                     {"c_limits", limit_json(limits[4])}};
  std::size_t total_points = 0;
  for (const OperationResult& r : result.operations) total_points += r.rows.size();
  data["points"] = total_points;
  data["mesh"] = mesh_json(part_mm, budget);
  const std::size_t plot_stride =
      std::max<std::size_t>(1, (total_points + budget.max_plot_points / 5 - 1) /
                                   std::max<std::size_t>(1, budget.max_plot_points / 5));
  const std::size_t axes_every = std::max<std::size_t>(
      1, (total_points + budget.max_axes - 1) / std::max<std::size_t>(1, budget.max_axes));
  data["decimation"] = {{"plot_stride", plot_stride}, {"axes_every", axes_every}};
  json ops = json::array(), markers = json::array();
  std::size_t marker_total = 0, plotted_total = 0;
  for (std::size_t k = 0; k < result.operations.size(); ++k) {
    const OperationResult& r = result.operations[k];
    ops.push_back(operation_series_json(r, machine, plot_stride, axes_every, plotted_total));
    add_markers(r, k, machine, budget, markers, marker_total);
  }
  data["operations"] = std::move(ops);
  data["markers"] = std::move(markers);
  data["marker_total"] = marker_total;
  data["plotted_points"] = plotted_total;
  data["findings"] = findings_json(result);
  // The page: static header and summary (readable without scripts), then the views.
  std::ostringstream page;
  write_header(page, result, toolpath, machine, options, run, assets);
  page << "</header>\n<section><h2>Summary</h2>" << summary_table(result)
       << "<p class=\"note\">&omega; and a: the synthetic angular velocity and acceleration of the "
          "rotary axes (the paper's eqs. 16&ndash;18) at the programmed feed; the cycle at the "
          "machine's limits (the feed schedule).</p></section>\n"
       << kHtmlPageBody << "\n<script>" << library_inside_element(assets.three_js, "three.min.js")
       << "</script>\n"
       << "<script>" << library_inside_element(assets.orbit_controls_js, "OrbitControls.js")
       << "</script>\n"
       << "<script>" << library_inside_element(assets.dygraph_js, "dygraph.min.js") << "</script>\n"
       << "<script type=\"application/json\" id=\"taxopt-data\">"
       << json_inside_script(data.dump(-1, ' ', false, json::error_handler_t::replace))
       << "</script>\n<script>" << kHtmlPageScript << "</script>\n"
       << kHtmlPageLicences << "</body></html>\n";
  return page.str();
}

}  // namespace taxopt
