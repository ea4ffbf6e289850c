#include "taxopt/io/linuxcnc_ini.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <system_error>

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

/// A value of the INI with where it was found.
struct IniValue {
  std::string text;
  int line = 0;
};

/// INI sections -> keys -> values (a key given twice, as HALCMD and HALFILE are, keeps all).
using Ini = std::map<std::string, std::multimap<std::string, IniValue>>;

Ini parse_ini(const std::string& text) {
  Ini ini;
  std::string section;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.empty() || s[0] == '#' || s[0] == ';') continue;
    if (s.front() == '[' && s.back() == ']') {
      section = s.substr(1, s.size() - 2);
      continue;
    }
    const std::size_t eq = s.find('=');
    if (eq == std::string::npos) continue;
    ini[section].insert({trim(s.substr(0, eq)), IniValue{trim(s.substr(eq + 1)), line}});
  }
  return ini;
}

const IniValue* first(const Ini& ini, const std::string& section, const std::string& key) {
  const auto s = ini.find(section);
  if (s == ini.end()) return nullptr;
  const auto k = s->second.find(key);
  return k == s->second.end() ? nullptr : &k->second;
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

}  // namespace

ImportedMachine machine_from_linuxcnc_ini(const std::string& ini_path) {
  const Ini ini = parse_ini(read_text(ini_path));
  ImportedMachine out;
  out.files_read.push_back(ini_path);
  const auto fail = [&](int line, const std::string& what) -> void {
    throw InputError(ini_path, line, what);
  };
  const IniValue* kins = first(ini, "KINS", "KINEMATICS");
  if (!kins) fail(0, "no [KINS] KINEMATICS: which kinematics is this machine?");
  std::string module;
  std::istringstream(kins->text) >> module;
  // xyzac-trt-kins and xyzbc-trt-kins (LinuxCNC's trtfuncs.c): the table-table machines.
  const bool bc = module == "xyzbc-trt-kins" || module == "xyzbc-trt";
  if (module != "xyzac-trt-kins" && module != "xyzac-trt" && !bc) {
    fail(kins->line, "KINEMATICS = " + kins->text +
                         ": only xyzac-trt-kins and xyzbc-trt-kins (A/C and B/C table-table "
                         "machines) are imported");
  }
  const std::string kins_prefix = bc ? "xyzbc-trt" : "xyzac-trt";
  const char tilt = bc ? 'B' : 'A';
  double unit_mm = 1.0;
  if (const IniValue* u = first(ini, "TRAJ", "LINEAR_UNITS")) {
    const std::string t = u->text;
    if (t == "inch" || t == "in" || t == "imperial") {
      unit_mm = kMmPerInch;
    } else if (t != "mm" || t.empty()) {
      if (t != "mm" && t != "metric") fail(u->line, "LINEAR_UNITS must be mm or inch");
    }
  } else {
    out.assumptions.push_back("[TRAJ] LINEAR_UNITS not given: mm");
  }
  const auto number = [&](const std::string& section, const std::string& key,
                          bool required) -> std::optional<double> {
    const IniValue* v = first(ini, section, key);
    if (!v) {
      if (required) fail(0, "[" + section + "] " + key + " is missing");
      return std::nullopt;
    }
    char* end = nullptr;
    const double d = std::strtod(v->text.c_str(), &end);
    if (end == v->text.c_str() || !std::isfinite(d) || trim(end) != "") {
      fail(v->line, "[" + section + "] " + key + " = " + v->text + " is not a number");
    }
    return d;
  };
  // The kinematics' pins, from the HALCMD lines and the HAL files beside the INI.
  HalPins hal;
  const auto hal_section = ini.find("HAL");
  const std::filesystem::path dir = std::filesystem::path(ini_path).parent_path();
  if (hal_section != ini.end()) {
    for (const auto& [key, v] : hal_section->second) {
      if (key == "HALCMD") hal.command(v.text);
      if (key == "HALFILE" || key == "POSTGUI_HALFILE") {
        if (v.text.rfind("LIB:", 0) == 0) continue;  // LinuxCNC's own library files
        const std::filesystem::path f = dir / v.text;
        // The error_code form: a name the system refuses (longer than NAME_MAX: a fuzzed INI)
        // threw filesystem_error through the importer.
        std::error_code ec;
        if (!std::filesystem::is_regular_file(f, ec) || f.extension() != ".hal") {
          out.assumptions.push_back("HAL file " + v.text + " not read (not a .hal file here)");
          continue;
        }
        out.files_read.push_back(f.string());
        std::istringstream lines(read_text(f.string()));
        for (std::string line; std::getline(lines, line);) hal.command(line);
      }
    }
  }
  const auto pin = [&](const std::string& name) {
    for (const std::string& prefix : {kins_prefix + "-kins.", kins_prefix + "."}) {
      if (const auto v = hal.value(prefix + name)) {
        // A value that is set but no number (or no machine's) is an error, never a 0.
        char* end = nullptr;
        const double d = std::strtod(v->c_str(), &end);
        if (end == v->c_str() || !std::isfinite(d) || trim(end) != "") {
          fail(0, "pin " + prefix + name + " = " + v->substr(0, 60) + " is not a number");
        }
        if (!(std::abs(d * unit_mm) <= 1e4)) {
          fail(0, "pin " + prefix + name + " = " + v->substr(0, 60) +
                      " lies beyond 1e4 mm: not a machine's");
        }
        return d * unit_mm;
      }
    }
    out.assumptions.push_back("pin " + name + " not set in the HAL commands: 0");
    return 0.0;
  };
  const double x_rot = pin("x-rot-point"), y_rot = pin("y-rot-point"), z_rot = pin("z-rot-point");
  // xyzac: the A axis lies y-offset and z-offset from the C axis's rot point; xyzbc: the B
  // axis x-offset and z-offset (trtfuncs.c; the tool offset pin is the tool length, set by
  // G43: taxopt's joints are the tip's).
  const double x_off = bc ? pin("x-offset") : 0.0, y_off = bc ? 0.0 : pin("y-offset");
  const double z_off = pin("z-offset");
  // A rotary axis's range: its [AXIS_] limits within its joint's (the joint's soft limits stop
  // the machine; LinuxCNC's xyzbc sample gives B +-36000 as an axis and -100..50 as joint 3).
  std::string coordinates = "XYZ" + std::string(1, tilt) + "C";
  if (const IniValue* c = first(ini, "TRAJ", "COORDINATES")) {
    coordinates.clear();
    for (char ch : c->text) {
      if (std::isalpha(static_cast<unsigned char>(ch))) {
        coordinates += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
    }
  }
  // The [JOINT_n] section of an axis that one joint drives ([TRAJ] COORDINATES names it once);
  // none where two joints drive it (a gantry) or none does.
  const auto joint_of = [&](const std::string& axis) -> std::optional<std::string> {
    const std::size_t j = coordinates.find(axis);
    if (j == std::string::npos || coordinates.find(axis, j + 1) != std::string::npos) {
      return std::nullopt;
    }
    return "JOINT_" + std::to_string(j);
  };
  const auto rotary_range = [&](const std::string& axis, bool required) {
    std::optional<double> lo = number("AXIS_" + axis, "MIN_LIMIT", required);
    std::optional<double> hi = number("AXIS_" + axis, "MAX_LIMIT", required);
    if (const auto joint = joint_of(axis)) {
      if (const auto l = number(*joint, "MIN_LIMIT", false)) lo = lo ? std::max(*lo, *l) : *l;
      if (const auto h = number(*joint, "MAX_LIMIT", false)) hi = hi ? std::min(*hi, *h) : *h;
    }
    if (lo && hi && !(*lo < *hi)) {
      fail(0, "[AXIS_" + axis + "] and its joint leave no range: " + number_text(*lo) + " to " +
                  number_text(*hi));
    }
    return std::make_pair(*lo, *hi);
  };

  // A joint's MAX_ACCELERATION where it differs from its axis's: with TCP on LinuxCNC plans the
  // axes at their [AXIS_] limits and the joints follow (Machine::joint_max_accel_per_s2).
  const auto joint_accel = [&](const std::string& axis,
                               const std::optional<double>& axis_accel) -> std::optional<double> {
    const auto joint = joint_of(axis);
    if (!joint) return std::nullopt;
    const auto a = number(*joint, "MAX_ACCELERATION", false);
    if (!a || (axis_accel && *a == *axis_accel)) return std::nullopt;
    return a;
  };

  std::ostringstream t;
  // The machine's name from the INI file's, as a TOML string: only plain characters kept.
  std::string name;
  for (char ch : std::filesystem::path(ini_path).stem().string()) {
    const unsigned char c = static_cast<unsigned char>(ch);
    name += std::isalnum(c) || ch == '-' || ch == '_' || ch == '.' ? ch : '_';
  }
  t << "# Made by taxopt machine --from-linuxcnc-ini " << name << ".ini\n";
  if (bc) {
    t << "# xyzbc-trt-kins: joints = Rot(Y, B)(Rot(Z, C)(p - rot) - d) + d + rot, d = (x-offset,\n"
      << "# 0, z-offset): sense -1 on B and C. Pivot: C through (x-rot-point, y-rot-point), B at\n"
      << "# x = x-rot-point + x-offset, z = z-rot-point + z-offset.\n"
      << "name = \"" << name << "\"\nkinematics = \"bc-table-table\"\n";
  } else {
    t << "# xyzac-trt-kins: tool axis (sin A sin C, sin A cos C, cos A): sense -1 on A and C.\n"
      << "# Pivot: C through (x-rot-point, y-rot-point), A at y = y-rot-point + y-offset,\n"
      << "# z = z-rot-point + z-offset.\n"
      << "name = \"" << name << "\"\nkinematics = \"ac-table-table\"\n";
  }
  for (const char* axis : {"X", "Y", "Z"}) {
    const std::string section = std::string("AXIS_") + axis;
    const auto lo = number(section, "MIN_LIMIT", true), hi = number(section, "MAX_LIMIT", true);
    t << "\n[axes." << axis << "]\nmin_mm = " << number_text(*lo * unit_mm)
      << "\nmax_mm = " << number_text(*hi * unit_mm) << "\n";
    if (const auto v = number(section, "MAX_VELOCITY", false)) {
      t << "max_velocity_mm_s = " << number_text(*v * unit_mm) << "\n";
    }
    const auto a = number(section, "MAX_ACCELERATION", false);
    if (a) t << "max_accel_mm_s2 = " << number_text(*a * unit_mm) << "\n";
    if (const auto ja = joint_accel(axis, a)) {
      t << "joint_max_accel_mm_s2 = " << number_text(*ja * unit_mm) << "\n";
    }
  }
  for (const std::string& axis : {std::string(1, tilt), std::string("C")}) {
    const std::string section = "AXIS_" + axis;
    const auto [lo, hi] = rotary_range(axis, true);
    t << "\n[axes." << axis << "]\nmin_deg = " << number_text(lo)
      << "\nmax_deg = " << number_text(hi) << "\nsense = -1\n";
    if (const auto v = number(section, "MAX_VELOCITY", false)) {
      t << "max_velocity_deg_s = " << number_text(*v) << "\n";
    }
    const auto a = number(section, "MAX_ACCELERATION", false);
    if (a) t << "max_accel_deg_s2 = " << number_text(*a) << "\n";
    if (const auto ja = joint_accel(axis, a)) {
      t << "joint_max_accel_deg_s2 = " << number_text(*ja) << "\n";
    }
  }
  const double z_top = *number("AXIS_Z", "MAX_LIMIT", true) * unit_mm;
  if (bc) {
    t << "\n[pivot]\nb_axis_x = " << number_text(x_rot + x_off)
      << "\nb_axis_z = " << number_text(z_rot + z_off);
  } else {
    t << "\n[pivot]\na_axis_y = " << number_text(y_rot + y_off)
      << "\na_axis_z = " << number_text(z_rot + z_off);
  }
  t << "\nc_axis_x = " << number_text(x_rot) << "\nc_axis_y = " << number_text(y_rot) << "\n"
    << "\n[gcode]\ndialect = \"linuxcnc\"\nmode = \"tcp\"\nfeed_mode = \"units-per-minute\"\n"
    << "decimals = 4\n# The retract before and after each operation: Z's upper limit.\n"
    << "retract_z_mm = " << number_text(z_top) << "\n";
  // A switchkins configuration that starts in identity kinematics (sparm=identityfirst, as
  // LinuxCNC's xyzac-trt sample does) switches TCP on with its remapped M428 and off with M429.
  bool remaps_428 = false;
  if (const auto rs = ini.find("RS274NGC"); rs != ini.end()) {
    const auto range = rs->second.equal_range("REMAP");
    for (auto it = range.first; it != range.second; ++it) {
      if (it->second.text.rfind("M428", 0) == 0) remaps_428 = true;
    }
  }
  if (kins->text.find("identityfirst") != std::string::npos) {
    if (!remaps_428) {
      fail(kins->line,
           "the kinematics start as identity (sparm=identityfirst) and no M428 is "
           "remapped to switch TCP on: give the switch as [gcode] tcp_on");
    }
    t << "# The kinematics start as identity (sparm=identityfirst): M428 switches TCP on.\n"
      << "tcp_on = [\"M428\"]\ntcp_off = [\"M429\"]\n";
    out.assumptions.push_back("switchkins, identity first: TCP switched on by M428, off by M429");
  }
  out.toml = t.str();
  parse_machine_toml(out.toml, ini_path + " (imported)");  // reads back, or says why not
  return out;
}

}  // namespace taxopt
