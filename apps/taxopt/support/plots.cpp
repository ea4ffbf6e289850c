#include "support/plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace taxopt {
namespace {

std::string esc(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&') {
      out += "&amp;";
    } else if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '"') {
      out += "&quot;";
    } else {
      out += c;
    }
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return std::string(buf) == "-0.0" ? "0.0" : buf;
}

/// A tick label: no trailing zeros, no "-0".
std::string tick_label(double v, double step) {
  if (std::abs(v) < 1e-9 * std::max(1.0, step)) v = 0.0;
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(buf, sizeof buf, "%.*f", std::min(decimals, 6), v);
  return buf;
}

/// Ticks 1, 2 or 5 x 10^k apart covering [lo, hi], about `want` of them.
std::vector<double> nice_ticks(double lo, double hi, int want, double& step) {
  const double range = std::max(hi - lo, 1e-12);
  const double raw = range / want;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  step = p * (raw / p < 1.5 ? 1.0 : raw / p < 3.5 ? 2.0 : raw / p < 7.5 ? 5.0 : 10.0);
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) {
    t.push_back(v);
  }
  return t;
}

constexpr double kW = 960, kH = 360, kL = 80, kR = 200, kT = 40, kB = 55;

}  // namespace

namespace {

/// One line plot drawn: its ranges (a log axis in decades), the transform to the page, then
/// header, grid and ticks, markers, series and frame with its legend.
class LinePlotSvg {
 public:
  explicit LinePlotSvg(const LinePlot& plot) : plot_(plot) { ranges(); }

  std::string draw() {
    out_ = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    out_ += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(kW) + "\" height=\"" +
            num(kH) + "\" viewBox=\"0 0 " + num(kW) + " " + num(kH) +
            "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n";
    out_ += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    out_ += "<text x=\"" + num(kL) + "\" y=\"24\" font-size=\"15\" font-weight=\"bold\">" +
            esc(plot_.title) + "</text>\n";
    grid();
    markers();
    series();
    frame();
    out_ += "</svg>\n";
    return out_;
  }

 private:
  static constexpr double kPw = kW - kL - kR, kPh = kH - kT - kB;

  void ranges() {
    x0_ = std::numeric_limits<double>::infinity(), x1_ = -x0_, y0_ = x0_, y1_ = -x0_;
    for (const PlotSeries& s : plot_.series) {
      for (double x : s.x) x0_ = std::min(x0_, x), x1_ = std::max(x1_, x);
      for (double y : s.y) {
        if (!std::isfinite(y)) continue;
        y0_ = std::min(y0_, y), y1_ = std::max(y1_, y);
      }
    }
    if (!(x1_ > x0_))
      x0_ = std::isfinite(x0_) ? x0_ - 1 : 0, x1_ = std::isfinite(x1_) ? x1_ + 1 : 1;
    if (!std::isfinite(y0_)) y0_ = 0, y1_ = 1;
    // Log axis: decades from the largest value down to 1e-4 of it at most.
    floor_y_ = 0.0;
    if (plot_.log_y) {
      floor_y_ = y1_ > 0 ? std::max(y1_ * 1e-4, y0_ > 0 ? y0_ : 0.0) : 1.0;
      y0_ = std::floor(std::log10(floor_y_));
      y1_ = std::ceil(std::log10(std::max(y1_, floor_y_ * 10)));
    } else {
      if (!(y1_ > y0_)) y0_ -= 1, y1_ += 1;
      const double pad = 0.05 * (y1_ - y0_);
      y0_ -= pad, y1_ += pad;
    }
  }

  double ty(double y) const {
    if (plot_.log_y) y = std::log10(std::max(y, floor_y_));
    return kT + kPh * (1.0 - (y - y0_) / (y1_ - y0_));
  }
  double tx(double x) const { return kL + kPw * (x - x0_) / (x1_ - x0_); }

  void grid() {
    // Grid and ticks.
    double xs = 1, ys = 1;
    for (double v : nice_ticks(x0_, x1_, 8, xs)) {
      out_ += "<line x1=\"" + num(tx(v)) + "\" y1=\"" + num(kT) + "\" x2=\"" + num(tx(v)) +
              "\" y2=\"" + num(kT + kPh) + "\" stroke=\"#e6e6e6\"/>\n";
      out_ += "<text x=\"" + num(tx(v)) + "\" y=\"" + num(kT + kPh + 16) +
              "\" text-anchor=\"middle\">" + tick_label(v, xs) + "</text>\n";
    }
    std::vector<double> yt;
    if (plot_.log_y) {
      for (double e = y0_; e <= y1_ + 1e-9; e += 1) yt.push_back(e);
    } else {
      yt = nice_ticks(y0_, y1_, 6, ys);
    }
    for (double v : yt) {
      const double py = plot_.log_y ? kT + kPh * (1.0 - (v - y0_) / (y1_ - y0_)) : ty(v);
      out_ += "<line x1=\"" + num(kL) + "\" y1=\"" + num(py) + "\" x2=\"" + num(kL + kPw) +
              "\" y2=\"" + num(py) + "\" stroke=\"#e6e6e6\"/>\n";
      const std::string label =
          plot_.log_y ? tick_label(std::pow(10.0, v), std::pow(10.0, v)) : tick_label(v, ys);
      out_ += "<text x=\"" + num(kL - 6) + "\" y=\"" + num(py + 4) + "\" text-anchor=\"end\">" +
              label + "</text>\n";
    }
  }

  void markers() {
    // Markers (segment boundaries), under the lines: full-height lines when they are few,
    // else ticks along the top edge (hundreds of lines would hide the curves).
    const bool few_markers = plot_.markers_x.size() <= 40;
    for (double m : plot_.markers_x) {
      out_ += "<line x1=\"" + num(tx(m)) + "\" y1=\"" + num(kT) + "\" x2=\"" + num(tx(m)) +
              "\" y2=\"" + num(few_markers ? kT + kPh : kT + 10) +
              "\" stroke=\"#e67e22\" stroke-width=\"0.8\"" +
              (few_markers ? " stroke-opacity=\"0.5\"" : "") + "/>\n";
    }
  }

  void series() {
    // Series, reduced to min and max per pixel column.
    for (const PlotSeries& s : plot_.series) {
      std::string pts;
      const std::size_t n = std::min(s.x.size(), s.y.size());
      std::size_t i = 0;
      while (i < n) {
        const int col = static_cast<int>(tx(s.x[i]));
        std::size_t lo = i, hi = i, e = i;
        while (e < n && static_cast<int>(tx(s.x[e])) == col) {
          if (s.y[e] < s.y[lo]) lo = e;
          if (s.y[e] > s.y[hi]) hi = e;
          ++e;
        }
        for (std::size_t k : {i, std::min(lo, hi), std::max(lo, hi), e - 1}) {
          pts += num(tx(s.x[k])) + "," + num(ty(s.y[k])) + " ";
        }
        i = e;
      }
      out_ += "<polyline fill=\"none\" stroke=\"" + s.colour + "\" stroke-width=\"1.4\"" +
              (s.dashed ? " stroke-dasharray=\"5,3\"" : "") + " points=\"" + pts + "\"/>\n";
    }
  }

  void frame() {
    // Frame, axis labels, legend.
    out_ += "<rect x=\"" + num(kL) + "\" y=\"" + num(kT) + "\" width=\"" + num(kPw) +
            "\" height=\"" + num(kPh) + "\" fill=\"none\" stroke=\"#444\"/>\n";
    out_ += "<text x=\"" + num(kL + kPw / 2) + "\" y=\"" + num(kH - 12) +
            "\" text-anchor=\"middle\">" + esc(plot_.x_label) + "</text>\n";
    out_ += "<text transform=\"translate(18," + num(kT + kPh / 2) +
            ") rotate(-90)\" text-anchor=\"middle\">" + esc(plot_.y_label) + "</text>\n";
    double ly = kT + 10;
    const double lx = kL + kPw + 16;
    for (const PlotSeries& s : plot_.series) {
      out_ += "<line x1=\"" + num(lx) + "\" y1=\"" + num(ly) + "\" x2=\"" + num(lx + 28) +
              "\" y2=\"" + num(ly) + "\" stroke=\"" + s.colour + "\" stroke-width=\"2\"" +
              (s.dashed ? " stroke-dasharray=\"5,3\"" : "") + "/>\n";
      out_ += "<text x=\"" + num(lx + 34) + "\" y=\"" + num(ly + 4) + "\">" + esc(s.label) +
              "</text>\n";
      ly += 20;
    }
    if (!plot_.markers_x.empty()) {
      out_ += "<line x1=\"" + num(lx + 14) + "\" y1=\"" + num(ly - 6) + "\" x2=\"" + num(lx + 14) +
              "\" y2=\"" + num(ly + 6) + "\" stroke=\"#e67e22\" stroke-width=\"2\"/>\n";
      out_ += "<text x=\"" + num(lx + 34) + "\" y=\"" + num(ly + 4) + "\">" +
              esc(plot_.markers_label) + "</text>\n";
    }
  }

  const LinePlot& plot_;
  double x0_ = 0.0, x1_ = 0.0, y0_ = 0.0, y1_ = 0.0, floor_y_ = 0.0;
  std::string out_;
};

}  // namespace

std::string svg_line_plot(const LinePlot& plot) { return LinePlotSvg(plot).draw(); }

namespace {

/// The C-space map's page: a disc of radius kMapR about (kMapX, kMapY), the tilt as radius.
constexpr double kMapW = 640, kMapH = 620, kMapX = 320, kMapY = 310, kMapR = 220;

/// "x,y" of a tilt and yaw on the map's disc.
std::string map_xy(double tilt_deg, double yaw_deg) {
  const double r = kMapR * tilt_deg / 90.0, b = deg_to_rad(yaw_deg);
  return num(kMapX + r * std::cos(b)) + "," + num(kMapY - r * std::sin(b));
}

/// Cells of the half grid (tilt >= 0), run-length per tilt row: free, or blocked within the
/// cone (outside it the disc's grey shows).
std::string map_cells(const CSpaceMap& map) {
  const CSpaceGrid& g = map.grid;
  const auto px = map_xy;
  std::string out;
  const double cos_dev = std::cos(deg_to_rad(map.max_deviation_deg));
  const double ai = deg_to_rad(map.input_tilt_deg), bi = deg_to_rad(map.input_yaw_deg);
  const double cell = g.cell_deg();
  for (int i = g.tilt_cells() / 2; i < g.tilt_cells(); ++i) {
    const double a = g.tilt_rad(i);
    const auto state = [&](int j) {
      const double b = g.yaw_rad(j);
      const double c = std::cos(a) * std::cos(ai) + std::sin(a) * std::sin(ai) * std::cos(b - bi);
      if (g.free(i, j)) return 1;
      return c >= cos_dev - 1e-12 ? 2 : 0;
    };
    int j = 0;
    while (j < g.yaw_cells()) {
      const int s = state(j);
      int e = j;
      while (e < g.yaw_cells() && state(e) == s) ++e;
      if (s != 0) {
        const double t0 = rad_to_deg(a) - cell / 2, t1 = rad_to_deg(a) + cell / 2;
        const double b0 = -180.0 + j * cell, b1 = -180.0 + e * cell;
        std::string pts;
        for (double b = b0; b <= b1 + 1e-9; b += cell) pts += px(t1, b) + " ";
        for (double b = b1; b >= b0 - 1e-9; b -= cell) pts += px(t0, b) + " ";
        const std::string colour = s == 1 ? "#bfe3b4" : "#d9534f";
        out += "<polygon points=\"" + pts + "\" fill=\"" + colour + "\" stroke=\"" + colour +
               "\" stroke-width=\"0.6\"/>\n";
      }
      j = e;
    }
  }
  return out;
}

/// Tilt rings and yaw spokes, labelled.
std::string map_rings() {
  const double cx = kMapX, cy = kMapY, R = kMapR;
  const auto px = map_xy;
  std::string out;
  for (double t : {30.0, 60.0, 90.0}) {
    out += "<circle cx=\"" + num(cx) + "\" cy=\"" + num(cy) + "\" r=\"" + num(R * t / 90.0) +
           "\" fill=\"none\" stroke=\"#777\" stroke-dasharray=\"3,3\"/>\n";
    const double rr = R * t / 90.0, b45 = deg_to_rad(45.0);
    out += "<text x=\"" + num(cx + rr * std::cos(b45) + 3) + "\" y=\"" +
           num(cy - rr * std::sin(b45) - 3) + "\" fill=\"#555\">" +
           num(t).substr(0, num(t).find('.')) + "\u00b0 tilt</text>\n";
  }
  for (const auto& [yaw, label] : {std::pair<double, const char*>{0.0, "T (yaw 0\u00b0)"},
                                   {90.0, "K (yaw 90\u00b0)"},
                                   {180.0, "-T"},
                                   {-90.0, "-K"}}) {
    out += "<line x1=\"" + num(cx) + "\" y1=\"" + num(cy) + "\" x2=\"" +
           px(90.0, yaw).substr(0, px(90.0, yaw).find(',')) + "\" y2=\"" +
           px(90.0, yaw).substr(px(90.0, yaw).find(',') + 1) + "\" stroke=\"#bbb\"/>\n";
    const double r = R + 14, b = deg_to_rad(yaw);
    out += "<text x=\"" + num(cx + r * std::cos(b)) + "\" y=\"" + num(cy - r * std::sin(b) + 4) +
           "\" text-anchor=\"" +
           (yaw == 0.0     ? "start"
            : yaw == 180.0 ? "end"
                           : "middle") +
           "\">" + label + "</text>\n";
  }
  return out;
}

/// The input and the output axes, and the legend.
std::string map_axes_and_legend(const CSpaceMap& map) {
  const double H = kMapH;
  const double cell = map.grid.cell_deg();
  const auto px = map_xy;
  std::string out;
  // Input and output axes.
  const std::string pin = px(map.input_tilt_deg, map.input_yaw_deg);
  const std::string pout = px(map.output_tilt_deg, map.output_yaw_deg);
  const auto xy = [](const std::string& p) {
    return std::pair<std::string, std::string>(p.substr(0, p.find(',')), p.substr(p.find(',') + 1));
  };
  out += "<circle cx=\"" + xy(pin).first + "\" cy=\"" + xy(pin).second +
         "\" r=\"7\" fill=\"none\" stroke=\"black\" stroke-width=\"2.5\"/>\n";
  out += "<circle cx=\"" + xy(pout).first + "\" cy=\"" + xy(pout).second +
         "\" r=\"5\" fill=\"#1f5fbf\" stroke=\"white\" stroke-width=\"1\"/>\n";
  // Legend.
  const double ly = H - 40;
  out += "<rect x=\"16\" y=\"" + num(ly - 10) + "\" width=\"14\" height=\"12\" fill=\"#bfe3b4\"/>";
  out += "<text x=\"36\" y=\"" + num(ly) + "\">free</text>\n";
  out += "<rect x=\"86\" y=\"" + num(ly - 10) + "\" width=\"14\" height=\"12\" fill=\"#d9534f\"/>";
  out += "<text x=\"106\" y=\"" + num(ly) + "\">blocked (tool meets part)</text>\n";
  out += "<rect x=\"276\" y=\"" + num(ly - 10) +
         "\" width=\"14\" height=\"12\" fill=\"#f2f2f2\" stroke=\"#999\"/>";
  out += "<text x=\"296\" y=\"" + num(ly) + "\">outside the " + num(map.max_deviation_deg) +
         "\u00b0 cone</text>\n";
  out += "<circle cx=\"23\" cy=\"" + num(ly + 18) +
         "\" r=\"6\" fill=\"none\" stroke=\"black\" stroke-width=\"2.5\"/>";
  out += "<text x=\"36\" y=\"" + num(ly + 22) + "\">input axis (tilt " + num(map.input_tilt_deg) +
         "\u00b0, yaw " + num(map.input_yaw_deg) + "\u00b0)</text>\n";
  out += "<circle cx=\"293\" cy=\"" + num(ly + 18) + "\" r=\"5\" fill=\"#1f5fbf\"/>";
  out += "<text x=\"306\" y=\"" + num(ly + 22) + "\">output axis (tilt " +
         num(map.output_tilt_deg) + "\u00b0, yaw " + num(map.output_yaw_deg) + "\u00b0)</text>\n";
  out +=
      "<text x=\"16\" y=\"44\" fill=\"#555\">seen down the contact normal N: radius = tilt, "
      "angle = yaw; cell " +
      num(cell) + "\u00b0</text>\n";
  return out;
}

}  // namespace

std::string svg_cspace_map(const CSpaceMap& map, const std::string& title) {
  const double W = kMapW, H = kMapH, cx = kMapX, cy = kMapY, R = kMapR;
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W) + "\" height=\"" + num(H) +
         "\" viewBox=\"0 0 " + num(W) + " " + num(H) +
         "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n";
  out += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  out +=
      "<text x=\"16\" y=\"24\" font-size=\"15\" font-weight=\"bold\">" + esc(title) + "</text>\n";
  out += "<circle cx=\"" + num(cx) + "\" cy=\"" + num(cy) + "\" r=\"" + num(R) +
         "\" fill=\"#f2f2f2\" stroke=\"#999\"/>\n";
  out += map_cells(map);
  out += map_rings();
  out += map_axes_and_legend(map);
  out += "</svg>\n";
  return out;
}

std::vector<std::pair<std::string, std::string>> job_plots(const JobResult& result) {
  std::vector<std::pair<std::string, std::string>> out;
  for (std::size_t k = 0; k < result.operations.size(); ++k) {
    const OperationResult& op = result.operations[k];
    const std::string stem = "op" + std::to_string(k + 1) + "-";
    // Points in path order: rows outside the passes (rapids between them) carry no arc.
    std::vector<const PointRow*> rows;
    for (const PointRow& r : op.rows) {
      if (rows.empty() || r.arc_mm >= rows.back()->arc_mm) rows.push_back(&r);
    }
    std::vector<double> arc, keys;
    for (const PointRow* r : rows) {
      arc.push_back(r->arc_mm);
      if (r->key) keys.push_back(r->arc_mm);
    }
    const auto column = [&](double PointRow::*field) {
      std::vector<double> v;
      for (const PointRow* r : rows) v.push_back(r->*field);
      return v;
    };
    const auto make = [&](const std::string& what, const std::string& unit, double PointRow::*b,
                          double PointRow::*a, bool log_y) {
      LinePlot p;
      p.title = op.name + ": " + what + " (" + unit + ")";
      p.x_label = "arc length along the path (mm)";
      p.y_label = what + " (" + unit + ")";
      p.log_y = log_y;
      p.series.push_back({"before (input axes)", arc, column(b), "#8c8c8c", true});
      p.series.push_back({"after", arc, column(a), "#1f5fbf", false});
      p.markers_x = keys;
      p.markers_label = "segment boundaries";
      return svg_line_plot(p);
    };
    out.emplace_back(stem + "angles-a.svg",
                     make(std::string(1, result.tilt_letter) + " angle", "deg",
                          &PointRow::tilt_axis_before_deg, &PointRow::tilt_axis_deg, false));
    out.emplace_back(stem + "angles-c.svg",
                     make("C angle", "deg", &PointRow::c_before_deg, &PointRow::c_deg, false));
    out.emplace_back(stem + "omega.svg",
                     make("synthetic angular velocity", "deg/s", &PointRow::omega_before_deg_s,
                          &PointRow::omega_deg_s, true));
    out.emplace_back(stem + "accel.svg",
                     make("synthetic angular acceleration", "deg/s\u00b2",
                          &PointRow::accel_before_deg_s2, &PointRow::accel_deg_s2, true));
    {
      // The feed the machine can hold at its limits (feed_schedule.hpp), on the feed moves.
      std::vector<double> feed_arc, before, after;
      for (const PointRow* r : rows) {
        if (!r->feed_mm_min || !r->feed_before_mm_min) continue;
        feed_arc.push_back(r->arc_mm);
        before.push_back(*r->feed_before_mm_min);
        after.push_back(*r->feed_mm_min);
      }
      if (!feed_arc.empty()) {
        LinePlot p;
        p.title = op.name + ": scheduled feed at the machine's limits (mm/min)";
        p.x_label = "arc length along the path (mm)";
        p.y_label = "feed (mm/min)";
        p.series.push_back({"before (input axes)", feed_arc, before, "#8c8c8c", true});
        p.series.push_back({"after", feed_arc, after, "#1f5fbf", false});
        p.markers_x = keys;
        p.markers_label = "segment boundaries";
        out.emplace_back(stem + "feed.svg", svg_line_plot(p));
      }
    }
    for (const CSpaceMap& m : op.cspace_maps) {
      out.emplace_back(stem + "cspace-" + std::to_string(m.index) + ".svg",
                       svg_cspace_map(m, op.name + ": C-space at point " + std::to_string(m.index) +
                                             " (" + m.why + ")"));
    }
  }
  return out;
}

}  // namespace taxopt
