#include "support/linuxcnc_ini.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <system_error>
#include <vector>

#include "taxopt/core/error.hpp"
#include "taxopt/core/types.hpp"
#include "taxopt/io/machine_file.hpp"
#include "util/input_file.hpp"
#include "util/text.hpp"

namespace taxopt {
namespace {

using detail::trim;

std::string read_text(const std::string& path) {
  // 16 MB is far beyond any INI or HAL file.
  return detail::read_input_file(path, std::uintmax_t{16} << 20, "a LinuxCNC INI or HAL file",
                                 "the LinuxCNC configuration file",
                                 "larger than 16 MB: not a LinuxCNC configuration file");
}

/// A value of the INI with where it was found (the INI, or a file it #INCLUDEs).
struct IniValue {
  std::string text;
  int line = 0;
  std::string file;
};

/// INI sections -> keys -> values (a key given twice, as HALCMD and HALFILE are, keeps all).
using Ini = std::map<std::string, std::multimap<std::string, IniValue>>;

/// Reads `path` into `ini`, with the files its `#INCLUDE name` lines name (LinuxCNC's INI
/// preprocessor, which the max5 sample uses: "#INCLUDE max5_base.inc"), relative to its folder,
/// at most 4 deep.
void parse_ini(const std::string& path, Ini& ini, std::vector<std::string>& files, int depth = 0) {
  if (depth > 4) throw InputError(path, 0, "#INCLUDE nested more than 4 deep");
  files.push_back(path);
  std::string section;
  std::istringstream in(read_text(path));
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.rfind("#INCLUDE", 0) == 0) {
      const std::string name = trim(s.substr(8));
      const std::filesystem::path f = std::filesystem::path(path).parent_path() / name;
      std::error_code ec;
      if (name.empty() || !std::filesystem::is_regular_file(f, ec)) {
        throw InputError(path, line, "#INCLUDE " + name + ": no such file beside the INI");
      }
      parse_ini(f.string(), ini, files, depth + 1);
      continue;
    }
    if (s.empty() || s[0] == '#' || s[0] == ';') continue;
    if (s.front() == '[' && s.back() == ']') {
      section = s.substr(1, s.size() - 2);
      continue;
    }
    const std::size_t eq = s.find('=');
    if (eq == std::string::npos) continue;
    ini[section].insert({trim(s.substr(0, eq)), IniValue{trim(s.substr(eq + 1)), line, path}});
  }
}

const IniValue* first(const Ini& ini, const std::string& section, const std::string& key) {
  const auto s = ini.find(section);
  if (s == ini.end()) return nullptr;
  const auto k = s->second.find(key);
  return k == s->second.end() ? nullptr : &k->second;
}

/// A HAL line with its `[SECTION]KEY` words replaced by the INI's values, as halcmd does when
/// LinuxCNC runs it with the INI (max5kins.hal: `setp maxkins.pivot-length [MAX]B_PIVOT_LENGTH`).
std::string substituted(const std::string& line, const Ini& ini) {
  std::string out;
  std::size_t i = 0;
  while (i < line.size()) {
    const std::size_t close = line[i] == '[' ? line.find(']', i) : std::string::npos;
    if (close != std::string::npos) {
      std::size_t end = close + 1;
      while (end < line.size() &&
             (std::isalnum(static_cast<unsigned char>(line[end])) || line[end] == '_')) {
        ++end;
      }
      const IniValue* v = end > close + 1 ? first(ini, line.substr(i + 1, close - i - 1),
                                                  line.substr(close + 1, end - close - 1))
                                          : nullptr;
      if (v) {
        out += v->text;
        i = end;
        continue;
      }
    }
    out += line[i++];
  }
  return out;
}

/// The HAL commands that set the kinematics' pins: `setp pin value`, `net signal pin...`,
/// `sets signal value`.
class HalPins {
 public:
  void command(const std::string& line) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) {
      if (x[0] == '#') break;
      w.push_back(x);
    }
    if (w.size() >= 3 && w[0] == "setp") pins_[w[1]] = w[2];
    if (w.size() >= 3 && w[0] == "sets") signals_[w[1]] = w[2];
    if (w.size() >= 3 && w[0] == "net") {
      for (std::size_t i = 2; i < w.size(); ++i) {
        if (w[i] != "<=" && w[i] != "=>" && w[i] != "<=>") net_of_[w[i]] = w[1];
      }
    }
  }
  std::optional<std::string> value(const std::string& pin) const {
    if (const auto p = pins_.find(pin); p != pins_.end()) return p->second;
    if (const auto n = net_of_.find(pin); n != net_of_.end()) {
      if (const auto s = signals_.find(n->second); s != signals_.end()) return s->second;
    }
    return std::nullopt;
  }

 private:
  std::map<std::string, std::string> pins_, signals_, net_of_;
};

std::string number_text(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  std::string s = os.str();
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

/// A kinematics module taxopt imports, from LinuxCNC's own sources (docs/kinematics.md).
struct KinsModule {
  std::string pin_prefix;  ///< its HAL pins' component name
  std::string kinematics;  ///< the machine file's name for it
  bool bc = false;         ///< a B tilt (about Y), else A (about X)
  RotaryLayout layout = RotaryLayout::TableTable;
  int tilt_sense = -1, c_sense = -1;
  std::string joints;   ///< the module's own joint order, where it has one (maxkins)
  std::string formula;  ///< the machine file's comment: the module's formula
};

/// The modules, each by the names a [KINS] KINEMATICS line gives it.
std::optional<KinsModule> kins_module(const std::string& module) {
  // clang-format off
  static const std::vector<std::pair<std::vector<std::string>, KinsModule>> modules = {
      {{"xyzac-trt-kins", "xyzac-trt"},
       {"xyzac-trt", "ac-table-table", false, RotaryLayout::TableTable, -1, -1, "",
        "# xyzac-trt-kins: tool axis (sin A sin C, sin A cos C, cos A): sense -1 on A and C.\n"
        "# Pivot: C through (x-rot-point, y-rot-point), A at y = y-rot-point + y-offset,\n"
        "# z = z-rot-point + z-offset.\n"}},
      {{"xyzbc-trt-kins", "xyzbc-trt"},
       {"xyzbc-trt", "bc-table-table", true, RotaryLayout::TableTable, -1, -1, "",
        "# xyzbc-trt-kins: joints = Rot(Y, B)(Rot(Z, C)(p - rot) - d) + d + rot, d = (x-offset,\n"
        "# 0, z-offset): sense -1 on B and C. Pivot: C through (x-rot-point, y-rot-point), B at\n"
        "# x = x-rot-point + x-offset, z = z-rot-point + z-offset.\n"}},
      // maxkins.c: joints = Rot(Z, -C) tip + L (-sin B, 0, cos B - 1), L its pivot-length pin;
      // "the direction of the B axis is the opposite of the conventional": sense -1 on B, +1 on
      // C. Its joints are X Y Z A B C whatever the INI's COORDINATES.
      {{"maxkins"},
       {"maxkins", "bc-head-table", true, RotaryLayout::HeadTable, -1, 1, "XYZABC",
        "# maxkins: joints = Rot(Z, -C) tip + L (-sin B, 0, cos B - 1), L the\n"
        "# pivot-length pin: the head tilts about B (sense -1), the table turns about C (+1).\n"}},
      // 5axiskins.c: joints = tip - L (sin B cos C, sin B sin C, 1 - cos B): sense -1 on B,
      // +1 on C.
      {{"5axiskins"},
       {"5axiskins", "bc-head-head", true, RotaryLayout::HeadHead, -1, 1, "",
        "# 5axiskins: joints = tip - L (sin B cos C, sin B sin C, 1 - cos B), L the\n"
        "# pivot-length pin: the head turns about C (+1) and tilts about B (-1).\n"}},
  };
  // clang-format on
  for (const auto& [names, m] : modules) {
    if (std::find(names.begin(), names.end(), module) != names.end()) return m;
  }
  return std::nullopt;
}

/// One import: the INI read, its kinematics known, its HAL's pins gathered; then the machine
/// file written section by section.
class Importer {
 public:
  explicit Importer(const std::string& ini_path) : ini_path_(ini_path) {
    parse_ini(ini_path, ini_, out_.files_read);
    const IniValue* kins = first(ini_, "KINS", "KINEMATICS");
    if (!kins) fail(nullptr, "no [KINS] KINEMATICS: which kinematics is this machine?");
    kins_ = kins;
    std::istringstream words(kins->text);
    std::string module;
    words >> module;
    const auto m = kins_module(module);
    if (!m) {
      fail(kins, "KINEMATICS = " + kins->text +
                     ": only xyzac-trt-kins and xyzbc-trt-kins (table-table), maxkins "
                     "(head-table) and 5axiskins (head-head) are imported");
    }
    module_ = *m;
    // A module parameter coordinates=... orders its joints (5axiskins coordinates=xyzbcwy).
    for (std::string w; words >> w;) {
      if (w.rfind("coordinates=", 0) == 0) coordinates_ = upper(w.substr(12));
    }
    tilt_ = module_.bc ? 'B' : 'A';
    joint_letters_ = joint_letters();
    read_units();
    read_angular_units();
    read_hal();
  }

  ImportedMachine run() {
    std::ostringstream t;
    write_header(t);
    write_axes(t);
    write_pivot(t);
    write_gcode(t);
    out_.toml = t.str();
    parse_machine_toml(out_.toml, ini_path_ + " (imported)");  // reads back, or says why not
    return out_;
  }

 private:
  [[noreturn]] void fail(const IniValue* at, const std::string& what) const {
    throw InputError(at ? at->file : ini_path_, at ? at->line : 0, what);
  }

  void read_units() {
    const IniValue* u = first(ini_, "TRAJ", "LINEAR_UNITS");
    if (!u) {
      out_.assumptions.push_back("[TRAJ] LINEAR_UNITS not given: mm");
      return;
    }
    const std::string v = u->text;
    // A name, or (older configurations, initraj.cc: "LINEAR_UNITS <float> units per mm") a
    // number: 1 for mm, 1/25.4 for inches (the max5 sample says 1.0).
    char* end = nullptr;
    const double per_mm = std::strtod(v.c_str(), &end);
    const bool number = end != v.c_str() && trim(end).empty();
    if (v == "inch" || v == "in" || v == "imperial" ||
        (number && std::abs(per_mm - 1.0 / kMmPerInch) < 1e-4)) {
      unit_mm_ = kMmPerInch;
    } else if (!(v == "mm" || v == "metric" || (number && std::abs(per_mm - 1.0) < 1e-9))) {
      fail(u, "LINEAR_UNITS must be mm or inch (or 1, 0.03937: units per mm), got " + v);
    }
  }

  /// [TRAJ] ANGULAR_UNITS: the unit of the rotary axes' limits, velocities and accelerations
  /// (degree, radian or grad; older configurations: a number of units per degree).
  void read_angular_units() {
    const IniValue* u = first(ini_, "TRAJ", "ANGULAR_UNITS");
    if (!u) {
      out_.assumptions.push_back("[TRAJ] ANGULAR_UNITS not given: degrees");
      return;
    }
    std::string v;
    for (char ch : u->text) v += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    char* end = nullptr;
    const double per_deg = std::strtod(v.c_str(), &end);
    const bool number = end != v.c_str() && trim(end).empty();
    const double rad_per_deg = deg_to_rad(1.0);
    if (v == "deg" || v == "degree" || v == "degrees" ||
        (number && std::abs(per_deg - 1.0) < 1e-9)) {
      deg_per_unit_ = 1.0;
    } else if (v == "rad" || v == "radian" || v == "radians" ||
               (number && std::abs(per_deg - rad_per_deg) < 1e-6)) {
      deg_per_unit_ = rad_to_deg(1.0);
    } else if (v == "grad" || v == "gon" || (number && std::abs(per_deg - 10.0 / 9.0) < 1e-6)) {
      deg_per_unit_ = 0.9;
    } else {
      fail(u,
           "ANGULAR_UNITS must be degree, radian or grad (or 1, 0.0174533, 1.11111: units "
           "per degree), got " +
               u->text);
    }
  }

  /// The kinematics' pins, from the HALCMD lines and the HAL files beside the INI.
  void read_hal() {
    const auto hal_section = ini_.find("HAL");
    if (hal_section == ini_.end()) return;
    const std::filesystem::path dir = std::filesystem::path(ini_path_).parent_path();
    for (const auto& [key, v] : hal_section->second) {
      if (key == "HALCMD") hal_.command(substituted(v.text, ini_));
      if (key != "HALFILE" && key != "POSTGUI_HALFILE") continue;
      if (v.text.rfind("LIB:", 0) == 0) continue;  // LinuxCNC's own library files
      const std::filesystem::path f = dir / v.text;
      // The error_code form: a name the system refuses (longer than NAME_MAX: a fuzzed INI)
      // threw filesystem_error through the importer.
      std::error_code ec;
      if (!std::filesystem::is_regular_file(f, ec) || f.extension() != ".hal") {
        out_.assumptions.push_back("HAL file " + v.text + " not read (not a .hal file here)");
        continue;
      }
      out_.files_read.push_back(f.string());
      std::istringstream lines(read_text(f.string()));
      for (std::string line; std::getline(lines, line);) hal_.command(substituted(line, ini_));
    }
  }

  std::optional<double> number(const std::string& section, const std::string& key,
                               bool required) const {
    const IniValue* v = first(ini_, section, key);
    if (!v) {
      if (required) fail(nullptr, "[" + section + "] " + key + " is missing");
      return std::nullopt;
    }
    char* end = nullptr;
    const double d = std::strtod(v->text.c_str(), &end);
    if (end == v->text.c_str() || !std::isfinite(d) || trim(end) != "") {
      fail(v, "[" + section + "] " + key + " = " + v->text + " is not a number");
    }
    return d;
  }

  /// A pin of the kinematics in mm; empty where no HAL command sets it to a value. The
  /// table-table modules' pins are named "<module>-kins.<pin>" in LinuxCNC's samples, some
  /// shops' HAL "<module>.<pin>"; the head modules' only "<module>.<pin>".
  std::optional<double> pin(const std::string& name) const {
    std::vector<std::string> prefixes;
    if (module_.layout == RotaryLayout::TableTable)
      prefixes.push_back(module_.pin_prefix + "-kins.");
    prefixes.push_back(module_.pin_prefix + ".");
    for (const std::string& prefix : prefixes) {
      if (const auto v = hal_.value(prefix + name)) {
        // A value that is set but no number (or no machine's) is an error, never a 0.
        char* end = nullptr;
        const double d = std::strtod(v->c_str(), &end);
        if (end == v->c_str() || !std::isfinite(d) || trim(end) != "") {
          fail(nullptr, "pin " + prefix + name + " = " + v->substr(0, 60) + " is not a number");
        }
        if (!(std::abs(d * unit_mm_) <= 1e4)) {
          fail(nullptr, "pin " + prefix + name + " = " + v->substr(0, 60) +
                            " lies beyond 1e4 mm: not a machine's");
        }
        return d * unit_mm_;
      }
    }
    return std::nullopt;
  }
  double pin_or_zero(const std::string& name) {
    if (const auto v = pin(name)) return *v;
    out_.assumptions.push_back("pin " + name + " not set in the HAL commands: 0");
    return 0.0;
  }

  /// The axis letters in joint order: the module's own (maxkins), else its coordinates=
  /// parameter, else [TRAJ] COORDINATES, else X Y Z, the tilt axis, C.
  std::string joint_letters() const {
    std::string order = module_.joints.empty() ? coordinates_ : module_.joints;
    if (order.empty()) {
      order = "XYZ" + std::string(1, tilt_) + "C";
      if (const IniValue* c = first(ini_, "TRAJ", "COORDINATES")) order = upper(c->text);
    }
    std::string letters;
    for (char ch : order) {
      if (std::isalpha(static_cast<unsigned char>(ch))) letters += ch;
    }
    return letters;
  }

  /// The [JOINT_n] section of an axis where one joint drives it; none where two do (a gantry)
  /// or none does.
  std::optional<std::string> joint_of(const std::string& axis) const {
    const std::size_t j = joint_letters_.find(axis);
    if (j == std::string::npos || joint_letters_.find(axis, j + 1) != std::string::npos) {
      return std::nullopt;
    }
    return "JOINT_" + std::to_string(j);
  }

  /// A rotary axis's range: its [AXIS_] limits within its joint's (the joint's soft limits stop
  /// the machine; LinuxCNC's xyzbc sample gives B +-36000 as an axis and -100..50 as joint 3).
  std::pair<double, double> rotary_range(const std::string& axis) const {
    std::optional<double> lo = number("AXIS_" + axis, "MIN_LIMIT", true);
    std::optional<double> hi = number("AXIS_" + axis, "MAX_LIMIT", true);
    if (const auto joint = joint_of(axis)) {
      if (const auto l = number(*joint, "MIN_LIMIT", false)) lo = std::max(*lo, *l);
      if (const auto h = number(*joint, "MAX_LIMIT", false)) hi = std::min(*hi, *h);
    }
    if (!(*lo < *hi)) {
      fail(nullptr, "[AXIS_" + axis + "] and its joint leave no range: " + number_text(*lo) +
                        " to " + number_text(*hi));
    }
    return {*lo * deg_per_unit_, *hi * deg_per_unit_};
  }

  /// A joint's MAX_ACCELERATION where it differs from its axis's: with TCP on LinuxCNC plans
  /// the axes at their [AXIS_] limits and the joints follow (Machine::joint_max_accel_per_s2).
  std::optional<double> joint_accel(const std::string& axis,
                                    const std::optional<double>& axis_accel) const {
    const auto joint = joint_of(axis);
    if (!joint) return std::nullopt;
    const auto a = number(*joint, "MAX_ACCELERATION", false);
    if (!a || (axis_accel && *a == *axis_accel)) return std::nullopt;
    return a;
  }

  void write_header(std::ostringstream& t) {
    // The machine's name from the INI file's, as a TOML string: only plain characters kept.
    for (char ch : std::filesystem::path(ini_path_).stem().string()) {
      const unsigned char c = static_cast<unsigned char>(ch);
      name_ += std::isalnum(c) || ch == '-' || ch == '_' || ch == '.' ? ch : '_';
    }
    t << "# Made by taxopt machine --from-linuxcnc-ini " << name_ << ".ini\n"
      << module_.formula << "name = \"" << name_ << "\"\nkinematics = \"" << module_.kinematics
      << "\"\n";
  }

  void write_axes(std::ostringstream& t) const {
    for (const char* axis : {"X", "Y", "Z"}) {
      const std::string section = std::string("AXIS_") + axis;
      const auto lo = number(section, "MIN_LIMIT", true), hi = number(section, "MAX_LIMIT", true);
      t << "\n[axes." << axis << "]\nmin_mm = " << number_text(*lo * unit_mm_)
        << "\nmax_mm = " << number_text(*hi * unit_mm_) << "\n";
      if (const auto v = number(section, "MAX_VELOCITY", false)) {
        t << "max_velocity_mm_s = " << number_text(*v * unit_mm_) << "\n";
      }
      const auto a = number(section, "MAX_ACCELERATION", false);
      if (a) t << "max_accel_mm_s2 = " << number_text(*a * unit_mm_) << "\n";
      if (const auto ja = joint_accel(axis, a)) {
        t << "joint_max_accel_mm_s2 = " << number_text(*ja * unit_mm_) << "\n";
      }
    }
    for (const std::string& axis : {std::string(1, tilt_), std::string("C")}) {
      const std::string section = "AXIS_" + axis;
      const auto [lo, hi] = rotary_range(axis);
      t << "\n[axes." << axis << "]\nmin_deg = " << number_text(lo)
        << "\nmax_deg = " << number_text(hi)
        << "\nsense = " << (axis == "C" ? module_.c_sense : module_.tilt_sense) << "\n";
      if (const auto v = number(section, "MAX_VELOCITY", false)) {
        t << "max_velocity_deg_s = " << number_text(*v * deg_per_unit_) << "\n";
      }
      const auto a = number(section, "MAX_ACCELERATION", false);
      if (a) t << "max_accel_deg_s2 = " << number_text(*a * deg_per_unit_) << "\n";
      if (const auto ja = joint_accel(axis, a)) {
        t << "joint_max_accel_deg_s2 = " << number_text(*ja * deg_per_unit_) << "\n";
      }
    }
  }

  void write_pivot(std::ostringstream& t) {
    if (module_.layout != RotaryLayout::TableTable) {
      // The head's pivot length: a number the configuration sets, never assumed (the bridge
      // mill sample nets it from its GUI's pivot_len plus the tool offset: not in its files).
      const auto length = pin("pivot-length");
      if (!length) {
        fail(kins_, "pin " + module_.pin_prefix +
                        ".pivot-length is not set to a number by the configuration's HAL "
                        "(setp, or sets on its signal): the head's pivot length is not known; "
                        "write the machine file by hand with [pivot] head_pivot_length");
      }
      // The tool's length is added by the job (LinuxCNC's HAL adds the tool offset to the pin).
      t << "\n[pivot]\n# From the tilt axis to the spindle's gauge line; taxopt adds the tool's "
           "gauge length.\nhead_pivot_length = "
        << number_text(*length) << "\n";
      return;
    }
    const double x_rot = pin_or_zero("x-rot-point"), y_rot = pin_or_zero("y-rot-point");
    const double z_rot = pin_or_zero("z-rot-point");
    // xyzac: the A axis lies y-offset and z-offset from the C axis's rot point; xyzbc: the B
    // axis x-offset and z-offset (trtfuncs.c; the tool offset pin is the tool length, set by
    // G43: taxopt's joints are the tip's).
    const double x_off = module_.bc ? pin_or_zero("x-offset") : 0.0;
    const double y_off = module_.bc ? 0.0 : pin_or_zero("y-offset");
    const double z_off = pin_or_zero("z-offset");
    // The rot-point pins are machine coordinates: with a work offset the job moves them.
    t << "\n[pivot]\n# In machine coordinates (the kinematics' rot-point pins).\nframe = "
         "\"machine\"";
    if (module_.bc) {
      t << "\nb_axis_x = " << number_text(x_rot + x_off)
        << "\nb_axis_z = " << number_text(z_rot + z_off);
    } else {
      t << "\na_axis_y = " << number_text(y_rot + y_off)
        << "\na_axis_z = " << number_text(z_rot + z_off);
    }
    t << "\nc_axis_x = " << number_text(x_rot) << "\nc_axis_y = " << number_text(y_rot) << "\n";
  }

  void write_gcode(std::ostringstream& t) {
    const double z_top = *number("AXIS_Z", "MAX_LIMIT", true) * unit_mm_;
    t << "\n[gcode]\ndialect = \"linuxcnc\"\nmode = \"tcp\"\nfeed_mode = \"units-per-minute\"\n"
      << "decimals = 4\n# The retract before and after each operation: Z's upper limit.\n"
      << "retract_z_mm = " << number_text(z_top) << "\n";
    // A switchkins configuration that starts in identity kinematics (sparm=identityfirst, as
    // LinuxCNC's xyzac-trt sample does) switches TCP on with its remapped M428, off with M429.
    bool remaps_428 = false;
    if (const auto rs = ini_.find("RS274NGC"); rs != ini_.end()) {
      const auto range = rs->second.equal_range("REMAP");
      for (auto it = range.first; it != range.second; ++it) {
        if (it->second.text.rfind("M428", 0) == 0) remaps_428 = true;
      }
    }
    if (kins_->text.find("identityfirst") != std::string::npos) {
      if (!remaps_428) {
        fail(kins_,
             "the kinematics start as identity (sparm=identityfirst) and no M428 is "
             "remapped to switch TCP on: give the switch as [gcode] tcp_on");
      }
      t << "# The kinematics start as identity (sparm=identityfirst): M428 switches TCP on.\n"
        << "tcp_on = [\"M428\"]\ntcp_off = [\"M429\"]\n";
      out_.assumptions.push_back(
          "switchkins, identity first: TCP switched on by M428, off by M429");
    }
  }

  static std::string upper(std::string s) {
    for (char& ch : s) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    return s;
  }

  std::string ini_path_;
  Ini ini_;
  ImportedMachine out_;
  const IniValue* kins_ = nullptr;
  KinsModule module_;
  std::string coordinates_;
  char tilt_ = 'A';
  std::string joint_letters_;  ///< joint_letters(), once the module is known
  double unit_mm_ = 1.0;
  /// Degrees per ANGULAR_UNITS unit.
  double deg_per_unit_ = 1.0;
  HalPins hal_;
  std::string name_;
};

}  // namespace

ImportedMachine machine_from_linuxcnc_ini(const std::string& ini_path) {
  return Importer(ini_path).run();
}

}  // namespace taxopt
