#include "support.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "taxopt/core/error.hpp"
#include "taxopt/geometry/surface.hpp"
#include "taxopt/io/gcode.hpp"

namespace taxopt::test {

TempDir::TempDir() {
  std::string templ = (std::filesystem::temp_directory_path() / "taxopt-test-XXXXXX").string();
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
  dir_ = buf.data();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::string replaced_once(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
}

bool file_exists(const std::string& path) { return std::filesystem::exists(path); }

std::string real_data(const std::string& name) {
  return std::string(TAXOPT_TEST_DATA) + "/real/" + name;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    out.push_back(text.substr(at, end - at));
    at = end == std::string::npos ? text.size() : end + 1;
  }
  return out;
}

std::size_t line_of(const std::vector<std::string>& lines, const std::string& what,
                    std::size_t from) {
  for (std::size_t i = from; i < lines.size(); ++i) {
    if (lines[i].find(what) != std::string::npos) return i;
  }
  return std::string::npos;
}

std::vector<std::string> real_skips(const std::string& name) {
  // SOLIDWORKS CAM's files: compensation in the control where they turn it on.
  if (name == "amorim-interface-glue.apt" || name == "amorim-wall-holes.apt") return {"CUTCOM"};
  if (name.rfind("peening-", 0) == 0) {
    return {"SATUTEST", "RECIPE",  "AIR",     "GLASS",   "FEEDOVER", "SAVERE",
            "STANDOFF", "SUBPROG", "SURFACE", "INITIAL", "REWIND"};
  }
  return {};
}

std::string real_flags(const std::string& name) {
  std::string out;
  for (const auto& w : real_skips(name)) out += " --skip-record " + w;
  // The NX files have no SPINDL (nor, the variable-axis one, a LOADTL): the production NX post
  // for the Haas wrote T0 M06 and S1000 M03 for them (tests/data/real-post); a user says so.
  if (name.rfind("mech491-", 0) == 0) out += " --spindle-rpm 1000 --tool-number 1";
  // CATIA's FROM stands before its LOADTL (the start position is an operation of its own),
  // and the peening file's SPINDLE records are made comments (real_text).
  if (name.rfind("peening-", 0) == 0) out += " --tool-number 1 --spindle-rpm 1000";
  return out;
}

std::string real_text(const std::string& name) {
  std::string text = read_file(real_data(name));
  if (name.rfind("peening-", 0) != 0) return text;
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    end = end == std::string::npos ? text.size() : end + 1;
    const std::string line = text.substr(start, end - start);
    // Line numbers stay: the record becomes a comment.
    out += line.rfind("SPINDLE/", 0) == 0 ? "$$ " + line : line;
    start = end;
  }
  return out;
}

std::string real_path(const std::string& name, const std::string& dir) {
  if (name.rfind("peening-", 0) != 0) return real_data(name);
  const std::string path = dir + "/" + name;
  write_file(path, real_text(name));
  return path;
}

Toolpath read_real(const std::string& name, ClReadOptions options) {
  for (const auto& w : real_skips(name)) options.skip_records.insert(w);
  return parse_cl(real_text(name), real_data(name), options);
}

RunResult run(const std::string& command) {
  TempDir tmp;
  const std::string out = tmp.path("out"), err = tmp.path("err");
  const std::string full = command + " >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(full.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

RunResult run_taxopt(const std::string& args) { return run(std::string(TAXOPT_EXE) + " " + args); }

int generate_small_sine(const TempDir& t) {
  return run_taxopt("generate --width 3 --length 20 --out-cls " + t.path("g.cls") + " --out-mesh " +
                    t.path("g.stl"))
      .code;
}

bool have_rs274() { return run("command -v rs274").code == 0; }

RunResult run_rs274(const std::string& ngc_path, std::vector<CanonMove>& moves,
                    const Rs274Options& options, std::vector<CanonMove>* all_moves) {
  TempDir tmp;
  // rs274 knows only the tools of its table: every T number the program uses is in it.
  std::set<long> tools;
  for (long t = 1; t < 100; ++t) tools.insert(t);
  const std::string program = read_file(ngc_path);
  for (std::size_t i = 0; i + 1 < program.size(); ++i) {
    if ((program[i] == 'T' || program[i] == 't') &&
        std::isdigit(static_cast<unsigned char>(program[i + 1])) &&
        (i == 0 || !std::isalpha(static_cast<unsigned char>(program[i - 1])))) {
      tools.insert(std::strtol(program.c_str() + i + 1, nullptr, 10));
    }
  }
  std::string table;
  int pocket = 0;
  for (long t : tools) {
    // rs274 on its own reads the tool table in inches, whatever the INI says.
    char z[32];
    std::snprintf(z, sizeof z, "%.8f", options.tool_length / 25.4);
    table += "T" + std::to_string(t) + " P" + std::to_string(++pocket) + " D6 Z" + z + " ;\n";
  }
  std::string dir = tmp.dir(), ini_arg;
  if (!options.ini.empty()) {
    const std::filesystem::path ini(options.ini);
    std::filesystem::copy(ini.parent_path(), tmp.path("config"),
                          std::filesystem::copy_options::recursive);
    dir = tmp.path("config");
    ini_arg = " -i " + ini.filename().string();
    if (options.stub_switchkins) {
      for (const char* m : {"428", "429", "430"}) {
        const std::string name = std::string(m) + "remap";
        write_file(dir + "/remap_subs/" + name + ".ngc",
                   "o<" + name + ">sub\n(MSG, kins switch M" + m + ")\no<" + name + ">endsub\n");
      }
    }
  }
  write_file(dir + "/tool.tbl", table);
  // rs274 keeps its parameter file (rs274ngc.var) in the working directory, and it opens
  // $HOME/.tool.mmap with O_TRUNC and maps it MAP_SHARED: two concurrent runs (ctest -j)
  // truncate each other's mapping and one dies of SIGBUS (exit 135). Each run gets its own
  // folder and its own HOME.
  const std::string abs = std::filesystem::absolute(ngc_path).string();
  RunResult r = run("cd " + dir + " && HOME=" + tmp.dir() + " rs274" + ini_arg +
                    " -t tool.tbl -v rs274ngc.var -g " + abs);
  moves.clear();
  double tool_length = 0.0;
  int kins = -1;
  std::istringstream in(r.out);
  std::string line;
  double feed_rate = 0.0;
  bool inverse_time = false;
  int plane = 2;  // the axis normal to the selected plane
  bool spindle_on = false, flood = false, mist = false;
  double spindle_speed = 0.0;
  int tool = 0;
  const auto stamp = [&](CanonMove& m) {
    m.spindle_on = spindle_on;
    m.tool = tool;
    m.coolant = flood || mist;
  };
  while (std::getline(in, line)) {
    if (const auto at = line.find("SET_SPINDLE_SPEED("); at != std::string::npos) {
      double spindle = 0.0;
      std::sscanf(line.c_str() + at + 18, "%*d, %lf", &spindle);
      spindle_speed = spindle;
    }
    if (line.find("START_SPINDLE_") != std::string::npos) spindle_on = spindle_speed > 0.0;
    if (line.find("STOP_SPINDLE_TURNING") != std::string::npos) spindle_on = false;
    if (const auto at = line.find("CHANGE_TOOL("); at != std::string::npos) {
      tool = std::atoi(line.c_str() + at + 12);
    }
    if (line.find("FLOOD_ON()") != std::string::npos) flood = true;
    if (line.find("FLOOD_OFF()") != std::string::npos) flood = false;
    if (line.find("MIST_ON()") != std::string::npos) mist = true;
    if (line.find("MIST_OFF()") != std::string::npos) mist = false;
    if (line.find("feed mode set to inverse time") != std::string::npos) inverse_time = true;
    if (line.find("feed mode set to units per minute") != std::string::npos) inverse_time = false;
    if (const auto at = line.find("SET_FEED_RATE("); at != std::string::npos) {
      feed_rate = std::strtod(line.c_str() + at + 14, nullptr);
    }
    if (line.find("kins switch M428\")") != std::string::npos) kins = 1;
    if (line.find("kins switch M429\")") != std::string::npos) kins = 0;
    if (const auto at = line.find("USE_TOOL_LENGTH_OFFSET("); at != std::string::npos) {
      double x = 0, y = 0;
      std::sscanf(line.c_str() + at + 23, "%lf %lf %lf", &x, &y, &tool_length);
    }
    if (line.find("SELECT_PLANE(CANON_PLANE_XY)") != std::string::npos) plane = 2;
    if (line.find("SELECT_PLANE(CANON_PLANE_XZ)") != std::string::npos) plane = 1;
    if (line.find("SELECT_PLANE(CANON_PLANE_YZ)") != std::string::npos) plane = 0;
    if (const auto at = line.find("ARC_FEED("); at != std::string::npos) {
      // ARC_FEED(first_end, second_end, first_axis, second_axis, rotation, axis_end, a, b, c):
      // first/second are X/Y (XY plane), Z/X (XZ), Y/Z (YZ); rotation > 0 counter-clockwise
      // about the plane's normal, |rotation| - 1 extra full turns.
      double fe, se, fc, sc, rot, ae;
      CanonMove m;
      if (std::sscanf(line.c_str() + at + 9, "%lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf", &fe,
                      &se, &fc, &sc, &rot, &ae, &m.a, &m.b, &m.c) != 9) {
        throw std::runtime_error("cannot parse rs274 line: " + line);
      }
      const int first = plane == 2 ? 0 : plane == 1 ? 2 : 1;
      const int second = plane == 2 ? 1 : plane == 1 ? 0 : 2;
      double start[3] = {0, 0, 0};
      if (!moves.empty())
        start[0] = moves.back().x, start[1] = moves.back().y, start[2] = moves.back().z;
      double end[3];
      end[first] = fe, end[second] = se, end[plane] = ae;
      const double a0 = std::atan2(start[second] - sc, start[first] - fc);
      const double a1 = std::atan2(end[second] - sc, end[first] - fc);
      double sweep = rot > 0 ? a1 - a0 : a0 - a1;
      while (sweep <= 1e-12) sweep += 2.0 * M_PI;
      sweep += 2.0 * M_PI * (std::fabs(rot) - 1.0);
      const double radius = std::hypot(start[first] - fc, start[second] - sc);
      m.feed = true;
      m.arc = true;
      m.arc_length = std::hypot(sweep * radius, end[plane] - start[plane]);
      m.x = end[0], m.y = end[1], m.z = end[2];
      m.feed_rate = feed_rate;
      m.inverse_time = inverse_time;
      m.tool_length = tool_length;
      m.kins = kins;
      stamp(m);
      moves.push_back(m);
      continue;
    }
    const bool feed = line.find("STRAIGHT_FEED(") != std::string::npos;
    const bool trav = line.find("STRAIGHT_TRAVERSE(") != std::string::npos;
    if (!feed && !trav) continue;
    CanonMove m;
    m.feed = feed;
    m.feed_rate = feed_rate;
    m.inverse_time = inverse_time;
    const auto open = line.find('(');
    if (std::sscanf(line.c_str() + open + 1, "%lf, %lf, %lf, %lf, %lf, %lf", &m.x, &m.y, &m.z, &m.a,
                    &m.b, &m.c) != 6) {
      throw std::runtime_error("cannot parse rs274 line: " + line);
    }
    m.tool_length = tool_length;
    m.kins = kins;
    stamp(m);
    moves.push_back(m);
  }
  if (all_moves) *all_moves = moves;
  // The program's own positioning moves (safe retract, table turn) belong to no point.
  try {
    // The tilt axis of the program: A, else (a B/C machine's program) B.
    std::vector<GcodeMove> ours;
    try {
      ours = read_gcode_moves(program, ngc_path);
    } catch (const InputError&) {
      ours = read_gcode_moves(program, ngc_path, GcodeDialect::LinuxCNC, {}, 'B');
    }
    if (ours.size() == moves.size()) {
      std::vector<CanonMove> kept;
      for (std::size_t i = 0; i < ours.size(); ++i) {
        if (!ours[i].positioning) kept.push_back(moves[i]);
      }
      moves.swap(kept);
    }
  } catch (const std::exception&) {
    // Not taxopt's subset: every move is kept, and the caller's comparison tells.
  }
  return r;
}

double path_length(const std::vector<CanonMove>& moves, std::size_t* arcs) {
  double path = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 1; i < moves.size(); ++i) {
    n += moves[i].arc ? 1 : 0;
    path += moves[i].arc ? moves[i].arc_length
                         : std::sqrt(std::pow(moves[i].x - moves[i - 1].x, 2) +
                                     std::pow(moves[i].y - moves[i - 1].y, 2) +
                                     std::pow(moves[i].z - moves[i - 1].z, 2));
  }
  if (arcs) *arcs = n;
  return path;
}

namespace {

Heightfield make(const std::string& name, std::function<double(double, double)> z) {
  Heightfield hf;
  hf.name = name;
  hf.z = z;
  hf.normal = [z](double x, double y) {
    const double h = 1e-5;
    const double zx = (z(x + h, y) - z(x - h, y)) / (2 * h);
    const double zy = (z(x, y + h) - z(x, y - h)) / (2 * h);
    return Vec3d(-zx, -zy, 1.0).normalized();
  };
  return hf;
}

}  // namespace

namespace {

/// A heightfield as a parametric surface (u = x, v = y) for tessellation.
struct HeightSurface {
  const Heightfield* hf;
  double x0, x1, y0, y1;
  double u_min() const { return x0; }
  double u_max() const { return x1; }
  double v_min() const { return y0; }
  double v_max() const { return y1; }
  SurfaceJet<double> jet(double u, double v) const {
    SurfaceJet<double> j;
    j.p = Vec3d(u, v, hf->z(u, v));
    return j;
  }
};

}  // namespace

std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// Nearest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3d closest_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

Vec3d brute_nearest(const TriangleMesh& m, const Vec3d& p) {
  Vec3d best = Vec3d::Zero();
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& f : m.faces) {
    const Vec3d q = closest_on_triangle(p, m.vertices[static_cast<std::size_t>(f[0])],
                                        m.vertices[static_cast<std::size_t>(f[1])],
                                        m.vertices[static_cast<std::size_t>(f[2])]);
    const double d = (q - p).norm();
    if (d < best_d) best_d = d, best = q;
  }
  return best;
}

TriangleMesh extruded_profile(const std::vector<Eigen::Vector2d>& profile, double y0, double y1,
                              int rows) {
  TriangleMesh m;
  const int n = static_cast<int>(profile.size());
  for (int j = 0; j <= rows; ++j) {
    const double y = y0 + (y1 - y0) * j / rows;
    for (const auto& p : profile) m.vertices.emplace_back(p.x(), y, p.y());
  }
  const auto id = [n](int j, int i) { return j * n + (i % n); };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < n; ++i) {
      m.faces.push_back({id(j, i), id(j + 1, i + 1), id(j + 1, i)});
      m.faces.push_back({id(j, i), id(j, i + 1), id(j + 1, i + 1)});
    }
  }
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : profile) c += p;
  c /= n;
  for (int end = 0; end < 2; ++end) {
    const int centre = static_cast<int>(m.vertices.size());
    m.vertices.emplace_back(c.x(), end == 0 ? y0 : y1, c.y());
    const int j = end == 0 ? 0 : rows;
    for (int i = 0; i < n; ++i) {
      if (end == 0) {
        m.faces.push_back({centre, id(j, i), id(j, i + 1)});
      } else {
        m.faces.push_back({centre, id(j, i + 1), id(j, i)});
      }
    }
  }
  return m;
}

TriangleMesh heightfield_mesh(const Heightfield& hf, double spacing_mm, double x0, double x1,
                              double y0, double y1) {
  const HeightSurface s{&hf, x0, x1, y0, y1};
  return tessellate(s, static_cast<int>(std::lround((x1 - x0) / spacing_mm)),
                    static_cast<int>(std::lround((y1 - y0) / spacing_mm)));
}

std::vector<Heightfield> random_heightfields(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Heightfield> out;
  {
    const double height = 10 + 15 * u(rng), width = 3 + 3 * u(rng), x0 = 20 + 10 * u(rng);
    const double skew = 0.3 * (u(rng) - 0.5);
    out.push_back(make("steep flank", [=](double x, double y) {
      return height * std::tanh((x - x0 + skew * y) / width);
    }));
  }
  {
    const double h = 8 + 12 * u(rng), s = 6 + 4 * u(rng), cx = 20 + 10 * u(rng),
                 cy = 20 + 10 * u(rng);
    out.push_back(make("bump", [=](double x, double y) {
      return h * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * s * s));
    }));
  }
  {
    const double h = 20 + 20 * u(rng), xw = 30 + 10 * u(rng), soft = 2.0 + 1.0 * u(rng);
    out.push_back(
        make("wall", [=](double x, double) { return h / (1.0 + std::exp(-(x - xw) / soft)); }));
  }
  return out;
}

void append_goto(GeneratedCl& g, std::ostream& os, const Vec3d& tip_mm, const Vec3d& axis,
                 bool rapid, const Vec3d& cc_mm, const Vec3d& centre_mm) {
  if (rapid) os << "RAPID\n";
  os << "GOTO/" << tip_mm.x() << "," << tip_mm.y() << "," << tip_mm.z() << "," << axis.x() << ","
     << axis.y() << "," << axis.z() << "\n";
  g.tips_mm.push_back(tip_mm);
  g.axes.push_back(axis);
  g.rapid.push_back(rapid);
  g.cc_mm.push_back(cc_mm);
  g.centres_mm.push_back(centre_mm);
}

GeneratedCl raster_cl(const Heightfield& hf, double r_mm, double tilt_deg, int passes,
                      double step_mm, double y0, double y1, double x0, double x1,
                      std::optional<double> clearance_z_mm) {
  GeneratedCl g;
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(6);
  os << "TOOL PATH/GENERATED_" << hf.name.substr(0, hf.name.find(' ')) << ",TOOL,BALL\n";
  os << "TLDATA/MILL," << 2 * r_mm << "," << r_mm << ",30.0,0.0,0.0\n";
  os << "MSYS/0,0,0,1,0,0,0,1,0\n";
  // As a CAM system writes them: the tool called and the spindle started (a program that
  // calls neither is refused).
  os << "LOADTL/1\nSPINDL/RPM,8000,CLW\n";
  const double tilt = deg_to_rad(tilt_deg);
  for (int p = 0; p < passes; ++p) {
    const double y = passes > 1 ? y0 + (y1 - y0) * p / (passes - 1) : y0;
    const int n = static_cast<int>(std::ceil((x1 - x0) / step_mm));
    for (int i = 0; i <= n; ++i) {
      const double x = x0 + (x1 - x0) * i / n;
      const Vec3d s(x, y, hf.z(x, y));
      const Vec3d nrm = hf.normal(x, y);
      // T: the tangent of the contact curve (x, y, z(x, y)) along the pass (eq. 4); the
      // tilt turns about K = N x T (eq. 11 with yaw 0).
      const double h = 1e-5;
      const Vec3d t = Vec3d(2 * h, 0.0, hf.z(x + h, y) - hf.z(x - h, y)).normalized();
      const Vec3d k = nrm.cross(t);
      const Vec3d v = Eigen::AngleAxisd(tilt, k) * nrm;
      const Vec3d tip = s + r_mm * nrm - r_mm * v;
      const Vec3d above = tip + 20.0 * v;  // approach and retract along the axis
      if (i == 0) {
        if (clearance_z_mm && p > 0) {
          const Vec3d up(above.x(), above.y(), *clearance_z_mm);
          append_goto(g, os, up, g.axes.back(), true, up, up + r_mm * g.axes.back());
        }
        append_goto(g, os, above, v, true, above, above + r_mm * v);
        os << "FEDRAT/MMPM,250.0\n";
      }
      append_goto(g, os, tip, v, false, s, s + r_mm * nrm);
      if (i == n) {
        append_goto(g, os, above, v, true, above, above + r_mm * v);
        if (clearance_z_mm) {
          const Vec3d up(above.x(), above.y(), *clearance_z_mm);
          append_goto(g, os, up, v, true, up, up + r_mm * v);
        }
      }
    }
  }
  os << "END-OF-PATH\n";
  g.text = os.str();
  return g;
}

Heightfield wall_heightfield() {
  Heightfield hf;
  hf.name = "wall";
  hf.z = [](double, double y) { return 30.0 / (1.0 + std::exp(-(y - 24.0) / 0.6)); };
  hf.normal = [z = hf.z](double x, double y) {
    const double e = 1e-5;
    return Vec3d(0.0, -(z(x, y + e) - z(x, y - e)) / (2 * e), 1.0).normalized();
  };
  return hf;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// The writer's plan of `prog` (GcodeProgram::blocks) against its text and the blocks read
/// back: one entry per line in order, every point's line a block that leads to that point,
/// every motion read back a motion block, the linearisation blocks counted.
void check_blocks(const GcodeProgram& prog, GcodeDialect dialect, char tilt_letter) {
  const auto lines = static_cast<std::size_t>(std::count(prog.text.begin(), prog.text.end(), '\n'));
  REQUIRE(prog.blocks.size() == lines);
  for (std::size_t l = 0; l < lines; ++l) REQUIRE(prog.blocks[l].line == static_cast<int>(l + 1));
  const auto block_at = [&](int line) {
    return prog.blocks.at(static_cast<std::size_t>(line - 1));
  };
  for (std::size_t k = 0; k < prog.emitted.size(); ++k) {
    for (std::size_t i = 0; i < prog.emitted[k].size(); ++i) {
      const int line = prog.emitted[k][i];
      if (line == 0) continue;
      const ProgramBlock b = block_at(std::abs(line));
      CHECK(b.operation == k);
      if (line > 0) CHECK(b.point == i);
      if (line < 0) CHECK(b.point > i);  // an arc's chord point: its end is on
      CHECK((b.kind == BlockKind::Point || b.kind == BlockKind::JointSafeRapid ||
             b.kind == BlockKind::Arc));
    }
  }
  std::size_t linearised = 0;
  for (const ProgramBlock& b : prog.blocks) linearised += b.kind == BlockKind::Linearised;
  CHECK(linearised == prog.linearised_blocks);
  const std::set<BlockKind> motions = {
      BlockKind::Retract,    BlockKind::TableTurn, BlockKind::Approach,       BlockKind::Point,
      BlockKind::Linearised, BlockKind::Arc,       BlockKind::JointSafeRapid, BlockKind::End};
  for (const GcodeMove& g : read_gcode_moves(prog.text, "p", dialect, prog.verbatim_lines,
                                             tilt_letter, prog.tool_calls)) {
    INFO("line " << g.line);
    CHECK(motions.count(block_at(g.line).kind) == 1);
  }
}

}  // namespace taxopt::test
