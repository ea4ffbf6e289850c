#include "taxopt/io/machine_file.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "dialects/dialect_rules.hpp"
#include "machine/template_block.hpp"
#include "taxopt/core/error.hpp"
#include "util/input_file.hpp"

namespace taxopt {
namespace {

int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

class MachineParser {
 public:
  explicit MachineParser(std::string source) : source_(std::move(source)) {}

  Machine parse(const std::string& text) {
    toml::table root;
    try {
      root = toml::parse(text, source_);
    } catch (const toml::parse_error& e) {
      throw InputError(source_, static_cast<int>(e.source().begin.line),
                       "not valid TOML: " + std::string(e.description()));
    }
    Machine m = default_machine();
    check_keys(
        root, "",
        {"name", "kinematics", "axes", "pivot", "gcode", "checks", "holder", "defaults", "setup"});
    if (auto* n = root.get("name")) m.name = string_of(*n, "name");
    parse_kinematics_and_axes(root, m);
    parse_checks_holder_defaults(root, m);
    parse_pivot(root, m);
    if (const toml::table* g = table_of(root, "gcode", false)) {
      parse_gcode_modes(root, *g, m);
      parse_program_identity(*g, m);
      parse_program_tolerances(*g, m);
      parse_program_end(*g, m);
      parse_template_blocks(*g, m);
    } else if (m.gcode.program.end_pose == EndPose::Home &&
               (!m.rotary.tilt.contains(0.0) || !m.rotary.c.contains(0.0))) {
      // The default end pose as the key would be checked: no program ends outside the ranges.
      fail(0, std::string("gcode.end_pose \"home\" (the default) turns ") + m.rotary.tilt_letter() +
                  " and C to 0, outside this machine's axis ranges; give [gcode] end_pose = "
                  "\"none\" (and home them in the footer)");
    }
    return m;
  }

 private:
  /// The kinematics, the rotary axes (range, sense, limits) and the linear ones.
  void parse_kinematics_and_axes(const toml::table& root, Machine& m) {
    const toml::node* kin = root.get("kinematics");
    if (!kin) fail(0, "missing key 'kinematics' (\"ac-table-table\" or \"bc-table-table\")");
    m.kinematics = string_of(*kin, "kinematics");
    if (!kinematics_layout(m.kinematics, m.rotary.tilt_about, m.rotary.layout)) {
      fail(line_of(*kin),
           "kinematics '" + m.kinematics + "' is not supported (" + kKinematicsNames + ")");
    }
    // The tilt axis: A about X, B about Y (machine_kinematics.hpp).
    const std::string tilt(1, m.rotary.tilt_letter());
    const toml::table* axes = table_of(root, "axes", true);
    check_keys(*axes, "axes", {"X", "Y", "Z", tilt, "C"});
    const toml::table* a_table = table_of(*axes, tilt, true, "axes.");
    const toml::table* c_table = table_of(*axes, "C", true, "axes.");
    parse_axis(*a_table, "axes." + tilt, m.rotary.tilt, false);
    parse_axis(*c_table, "axes.C", m.rotary.c, true);
    parse_limits(*a_table, "axes." + tilt, "deg", m, Joint::Tilt);
    parse_limits(*c_table, "axes.C", "deg", m, Joint::C);
    for (Joint j : {Joint::X, Joint::Y, Joint::Z}) {
      const std::string name = to_string(j);
      if (const toml::table* t = table_of(*axes, name, false, "axes.")) {
        check_keys(*t, "axes." + name,
                   {"min_mm", "max_mm", "max_velocity_mm_s", "max_accel_mm_s2", "max_jerk_mm_s3",
                    "joint_max_accel_mm_s2"});
        parse_limits(*t, "axes." + name, "mm", m, j);
        const toml::node* lo = t->get("min_mm");
        const toml::node* hi = t->get("max_mm");
        if (lo || hi) {
          if (!lo || !hi)
            fail(line_of(lo ? *lo : *hi), "axes." + name + " needs min_mm and max_mm");
          auto& range = m.linear_range[static_cast<std::size_t>(j)];
          range.min_mm = number_of(*lo, "axes." + name + ".min_mm");
          range.max_mm = number_of(*hi, "axes." + name + ".max_mm");
          if (!(range.min_mm < range.max_mm)) {
            fail(line_of(*lo), "axes." + name + ": min_mm must be less than max_mm");
          }
        }
      }
    }
  }

  /// A number >= 0 (or > 0) under `key`, where given.
  std::optional<double> positive(const toml::table& t, const std::string& where,
                                 const std::string& key, bool zero_ok) const {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    const double v = number_of(*n, where + "." + key);
    if (!(zero_ok ? v >= 0.0 : v > 0.0)) {
      fail(line_of(*n), where + "." + key + (zero_ok ? " must be >= 0" : " must be positive"));
    }
    return v;
  }

  /// [checks], [holder], [setup] and [defaults].
  void parse_checks_holder_defaults(const toml::table& root, Machine& m) {
    if (const toml::table* c = table_of(root, "checks", false)) {
      check_keys(*c, "checks", {"shank_clearance_mm", "holder_clearance_mm"});
      m.shank_clearance_mm = positive(*c, "checks", "shank_clearance_mm", true);
      m.holder_clearance_mm = positive(*c, "checks", "holder_clearance_mm", true);
    }
    if (const toml::table* h = table_of(root, "holder", false)) {
      check_keys(*h, "holder", {"radius_mm", "length_mm", "gauge_length_mm"});
      m.holder_radius_mm = positive(*h, "holder", "radius_mm", false);
      m.holder_length_mm = positive(*h, "holder", "length_mm", false);
      m.holder_gauge_length_mm = positive(*h, "holder", "gauge_length_mm", false);
      if (!m.holder_radius_mm) fail(0, "[holder] needs radius_mm");
    }
    if (const toml::table* s = table_of(root, "setup", false)) {
      check_keys(*s, "setup", {"work_offset_mm"});
      if (const toml::node* n = s->get("work_offset_mm")) {
        const auto* list = n->as_array();
        if (!list || list->size() != 3) {
          fail(line_of(*n),
               "setup.work_offset_mm must be [x, y, z]: the program's zero in machine "
               "coordinates, mm");
        }
        Vec3d offset;
        for (std::size_t q = 0; q < 3; ++q) {
          offset[static_cast<Eigen::Index>(q)] =
              number_of(*list->get(q), std::string("setup.work_offset_mm's ") + "XYZ"[q]);
        }
        m.work_offset_mm = offset;
      }
    }
    if (const toml::table* d = table_of(root, "defaults", false)) {
      // What an operation runs with where its CL file says nothing (a machinist's review,
      // tests/test_program.cpp): never guessed.
      check_keys(*d, "defaults", {"spindle_rpm", "tool_number"});
      if (const toml::node* n = d->get("spindle_rpm")) {
        const double rpm = number_of(*n, "defaults.spindle_rpm");
        if (!(rpm >= 1.0 && rpm <= 2e5)) {
          fail(line_of(*n), "defaults.spindle_rpm must be within [1, 200000] rpm");
        }
        m.default_spindle_rpm = rpm;
      }
      if (const toml::node* n = d->get("tool_number")) {
        m.default_tool_number = whole(*n, "defaults.tool_number", 1, 99999, "");
      }
    }
  }

  /// [pivot]: a head's pivot length, or where a table's rotary axes lie.
  void parse_pivot(const toml::table& root, Machine& m) {
    const bool head = m.rotary.layout != RotaryLayout::TableTable;
    const toml::table* given = table_of(root, "pivot", false);
    const auto needs_length = [&](int line) {
      // Never assumed (0 was taken silently, issue 63.12): the tool's joints depend on it.
      fail(line,
           "a head machine needs [pivot] head_pivot_length: from the tilt axis to the spindle's "
           "gauge line, mm (0 where the controller's kinematics carry none, as LinuxCNC's max5 "
           "sample)");
    };
    if (head && !given) needs_length(0);
    if (given) {
      choose(*given, "pivot", "frame",
             {{"workpiece", PivotFrame::Workpiece}, {"machine", PivotFrame::Machine}},
             m.pivot_frame);
    }
    if (const toml::table* pivot = given; pivot && head) {
      // A head: its pivot length (tilt axis to the spindle's gauge line), and for a head-table
      // machine where C turns the table.
      check_keys(*pivot, "pivot", {"head_pivot_length", "c_axis_x", "c_axis_y", "frame"});
      if (!pivot->get("head_pivot_length")) needs_length(line_of(*pivot));
      const double pivot_mm = length_or(*pivot, "pivot", "head_pivot_length", 0.0);
      m.head_pivot_length_mm = pivot_mm;
      if (!(pivot_mm >= 0.0 && pivot_mm <= 5000.0)) {
        fail(line_of(*pivot->get("head_pivot_length")),
             "pivot.head_pivot_length must be within [0, 5000] mm");
      }
      m.rotary.head_length_mm = pivot_mm;
      m.rotary.c_axis_point_mm = Vec3d(length_or(*pivot, "pivot", "c_axis_x", 0.0),
                                       length_or(*pivot, "pivot", "c_axis_y", 0.0), 0.0);
    } else if (pivot) {
      if (m.rotary.tilt_about == TiltAxis::Y) {
        check_keys(*pivot, "pivot", {"b_axis_x", "b_axis_z", "c_axis_x", "c_axis_y", "frame"});
        m.rotary.tilt_axis_point_mm = Vec3d(length_or(*pivot, "pivot", "b_axis_x", 0.0), 0.0,
                                            length_or(*pivot, "pivot", "b_axis_z", 0.0));
      } else {
        check_keys(*pivot, "pivot", {"a_axis_y", "a_axis_z", "c_axis_x", "c_axis_y", "frame"});
        m.rotary.tilt_axis_point_mm = Vec3d(0.0, length_or(*pivot, "pivot", "a_axis_y", 0.0),
                                            length_or(*pivot, "pivot", "a_axis_z", 0.0));
      }
      m.rotary.c_axis_point_mm = Vec3d(length_or(*pivot, "pivot", "c_axis_x", 0.0),
                                       length_or(*pivot, "pivot", "c_axis_y", 0.0), 0.0);
    }
  }

  /// [gcode]'s dialect, mode, feed words and decimals.
  void parse_gcode_modes(const toml::table& root, const toml::table& gt, Machine& m) {
    const toml::table* g = &gt;
    const bool head = m.rotary.layout != RotaryLayout::TableTable;
    // clang-format off
    check_keys(*g, "gcode",
               {"dialect", "mode", "feed_mode", "feed_reference", "max_feed_ratio", "decimals",
                "feed_decimals", "program_name", "program_number", "work_offset", "coolant",
                "header", "footer", "tool_change", "tcp_on", "tcp_off", "safe_retract",
                "retract_z_mm", "linearise_tolerance_mm", "blend_tolerance_mm",
                "approach_clearance_mm", "index_threshold_deg", "end_pose", "end_park_xy_mm"});
    // clang-format on
    std::vector<std::pair<std::string, GcodeDialect>> dialects;
    for (const GcodeDialect d : gcode_dialects()) dialects.emplace_back(to_string(d), d);
    choose(*g, "gcode", "dialect", dialects, m.gcode.dialect);
    choose(*g, "gcode", "mode", {{"tcp", GcodeMode::Tcp}, {"machine", GcodeMode::Machine}},
           m.gcode.mode);
    if (m.gcode.mode == GcodeMode::Machine && head) {
      // In machine mode every block would carry the tip swung about the pivot by the pivot
      // length plus this tool's length (maxkins, 5axiskins): taxopt writes head machines
      // with the controller's TCP, which takes the tool length from its own table.
      fail(line_of(*g->get("mode")),
           "gcode.mode \"machine\" on a " + m.kinematics +
               " machine is not written (each block would depend on the tool's length about "
               "the head's pivot): use mode \"tcp\" (the controller's G43.4, TRAORI, M128 or "
               "LinuxCNC's head kinematics)");
    }
    if (m.gcode.mode == GcodeMode::Machine && !table_of(root, "pivot", false)) {
      // Machine mode writes joint positions about the rotary axes' pivots: a file without
      // them would post every point about a pivot at 0, silently (a machinist's review,
      // tests/test_program.cpp).
      fail(line_of(*g->get("mode")),
           std::string("gcode.mode \"machine\" needs the machine's [pivot] (") +
               (m.rotary.tilt_about == TiltAxis::Y ? "b_axis_x, b_axis_z" : "a_axis_y, a_axis_z") +
               ", c_axis_x, c_axis_y: where the rotary axes lie in machine coordinates, from "
               "the machine's kinematics); give it, even as zeros, or use mode \"tcp\"");
    }
    choose(
        *g, "gcode", "feed_mode",
        {{"units-per-minute", FeedMode::UnitsPerMinute}, {"inverse-time", FeedMode::InverseTime}},
        m.gcode.feed_mode);
    choose(*g, "gcode", "feed_reference",
           {{"cutter-path", FeedReference::CutterPath}, {"tip", FeedReference::Tip}},
           m.gcode.feed_reference);
    if (!has_inverse_time(m.gcode.dialect) && m.gcode.feed_mode == FeedMode::InverseTime) {
      fail(line_of(*g->get("feed_mode")),
           "gcode.feed_mode \"inverse-time\" is not written for the " +
               std::string(to_string(m.gcode.dialect)) +
               " dialect (its ISO mode has no G93); use \"units-per-minute\"");
    }
    if (auto* n = g->get("max_feed_ratio")) {
      m.gcode.max_feed_ratio = number_of(*n, "gcode.max_feed_ratio");
      if (!(m.gcode.max_feed_ratio >= 1.0 && m.gcode.max_feed_ratio <= 100.0)) {
        fail(line_of(*n),
             "gcode.max_feed_ratio must be within [1, 100] (times the programmed "
             "feed)");
      }
    }
    const std::string dialect = to_string(m.gcode.dialect);
    if (auto* n = g->get("decimals")) {
      const int most = max_decimals(m.gcode.dialect);
      m.gcode.decimals = whole(*n, "gcode.decimals", 0, most, " (the most " + dialect + " takes)");
    }
    if (auto* n = g->get("feed_decimals")) {
      const int most = max_feed_decimals(m.gcode.dialect);
      m.gcode.feed_decimals =
          whole(*n, "gcode.feed_decimals", 0, most, " (the most " + dialect + " takes)");
    }
  }

  /// The program's name, number, work offset, coolant and retract.
  void parse_program_identity(const toml::table& gt, Machine& m) {
    const toml::table* g = &gt;
    ProgramTemplate& t = m.gcode.program;
    if (auto* n = g->get("program_name")) {
      t.name = string_of(*n, "gcode.program_name");
      if (!program_name_characters_ok(t.name)) {
        fail(line_of(*n), "gcode.program_name may hold letters, digits, '_' and '-' only");
      }
      if (t.name.empty() || t.name.size() > 24) {
        fail(line_of(*n), "gcode.program_name must have 1 to 24 characters");
      }
    }
    if (auto* n = g->get("program_number")) {
      const gcode::DialectRules& rules = gcode::rules_of(m.gcode.dialect);
      const int most = rules.max_program_number();
      t.number =
          whole(*n, "gcode.program_number", 1, most,
                std::string(" (") + rules.name() + "'s O1 to O" + std::to_string(most) + ")");
    }
    if (auto* n = g->get("work_offset")) {
      t.work_offset = string_of(*n, "gcode.work_offset");
      if (t.work_offset.empty()) fail(line_of(*n), "gcode.work_offset is empty (\"none\"?)");
      if (t.work_offset != "none") {
        check_block(*n, t.work_offset, "gcode.work_offset", m.gcode.dialect);
      }
    }
    choose(*g, "gcode", "coolant",
           {{"none", Coolant::None}, {"flood", Coolant::Flood}, {"mist", Coolant::Mist}},
           t.coolant);
    choose(*g, "gcode", "safe_retract",
           {{"machine-z", SafeRetract::MachineZ}, {"none", SafeRetract::None}}, t.retract);
  }

  /// The program's retract height and tolerances.
  void parse_program_tolerances(const toml::table& gt, Machine& m) {
    const toml::table* g = &gt;
    ProgramTemplate& t = m.gcode.program;
    t.retract_z_mm = length_or(*g, "gcode", "retract_z_mm", t.retract_z_mm);
    if (auto* n = g->get("linearise_tolerance_mm")) {
      t.linearise_tolerance_mm = number_of(*n, "gcode.linearise_tolerance_mm");
      if (t.linearise_tolerance_mm < 0.0 ||
          (t.linearise_tolerance_mm > 0.0 && t.linearise_tolerance_mm < 1e-3)) {
        fail(line_of(*n),
             "gcode.linearise_tolerance_mm must be 0 (off) or at least 0.001 mm, the written "
             "words' resolution (finer, each move is cut into thousands of blocks)");
      }
    }
    if (auto* n = g->get("blend_tolerance_mm")) {
      t.blend_tolerance_mm = number_of(*n, "gcode.blend_tolerance_mm");
      if (!(t.blend_tolerance_mm >= 0.0 && t.blend_tolerance_mm <= 1.0)) {
        fail(line_of(*n), "gcode.blend_tolerance_mm must be within [0, 1] mm (0: exact path)");
      }
    }
    if (auto* n = g->get("approach_clearance_mm")) {
      t.approach_clearance_mm = number_of(*n, "gcode.approach_clearance_mm");
      if (!(t.approach_clearance_mm >= 0.0 && t.approach_clearance_mm <= 1000.0)) {
        fail(line_of(*n), "gcode.approach_clearance_mm must be within [0, 1000] mm");
      }
    }
    if (auto* n = g->get("index_threshold_deg")) {
      t.index_threshold_deg = number_of(*n, "gcode.index_threshold_deg");
      if (!(t.index_threshold_deg >= 0.0 && t.index_threshold_deg <= 360.0)) {
        fail(line_of(*n), "gcode.index_threshold_deg must be within [0, 360] deg");
      }
    }
  }

  /// How the program ends: the rotaries' home turn and the park.
  void parse_program_end(const toml::table& gt, Machine& m) {
    const toml::table* g = &gt;
    ProgramTemplate& t = m.gcode.program;
    choose(*g, "gcode", "end_pose", {{"home", EndPose::Home}, {"none", EndPose::None}}, t.end_pose);
    if (t.end_pose == EndPose::Home &&
        (!m.rotary.tilt.contains(0.0) || !m.rotary.c.contains(0.0))) {
      fail(line_of(*g), std::string("gcode.end_pose \"home\" turns ") + m.rotary.tilt_letter() +
                            " and C to 0, outside this machine's axis ranges; use \"none\" "
                            "(and home them in the footer)");
    }
    if (auto* n = g->get("end_park_xy_mm")) {
      const auto* list = n->as_array();
      if (!list || list->size() != 2) {
        fail(line_of(*n), "gcode.end_park_xy_mm must be [x, y] in machine coordinates, mm");
      }
      std::array<double, 2> xy{};
      for (std::size_t q = 0; q < 2; ++q) {
        const std::string what = std::string("gcode.end_park_xy_mm's ") + "XY"[q];
        xy[q] = number_of(*list->get(q), what);
        // Without a travel: within 100 m of the machine's zero (1e9 was taken, issue 63.12).
        if (!(std::abs(xy[q]) <= 1e5)) fail(line_of(*n), what + " must be within [-1e5, 1e5] mm");
        if (!m.linear_range[q].contains(xy[q])) {
          fail(line_of(*n),
               what + " lies outside the machine's travel ([axes." + "XY"[q] + "] min_mm, max_mm)");
        }
      }
      if (t.retract == SafeRetract::None) {
        fail(line_of(*n),
             "gcode.end_park_xy_mm needs the safe retract (safe_retract "
             "\"machine-z\"): the table moves under the tool only with it up");
      }
      t.end_park_xy_mm = xy;
    }
  }

  /// The program template's blocks: header, footer, tool change, TCP on and off.
  void parse_template_blocks(const toml::table& gt, Machine& m) {
    const toml::table* g = &gt;
    ProgramTemplate& t = m.gcode.program;
    for (const auto& [key, list] : kTemplateLists) {
      std::vector<std::string>* out = &(t.*list);
      const toml::node* n = g->get(key);
      if (!n) continue;
      const std::string what = std::string("gcode.") + key;
      if (!n->is_array()) fail(line_of(*n), what + " must be a list of blocks (strings)");
      if (std::string(key) == "tool_change") {
        // The program is checked for the tool it calls: the template must call ours.
        bool calls = false;
        for (const toml::node& e : *n->as_array()) {
          calls = calls || (e.is_string() &&
                            e.value<std::string>().value().find("{tool}") != std::string::npos);
        }
        if (!calls) {
          fail(line_of(*n), what + " " + kToolChangeCallsTool);
        }
      }
      for (const toml::node& e : *n->as_array()) {
        const std::string b = string_of(e, what + " entries");
        check_block(e, b, what, m.gcode.dialect, std::string(key) == "footer");
        out->push_back(b);
      }
    }
    check_no_tcp_switch(*g, t);
  }

  /// A header, footer or tool change that switches TCP on or off (a word of the tcp_on or
  /// tcp_off blocks, as M428 on LinuxCNC's sample) would turn it on before the table turns and
  /// the tool length comes on (the order LinuxCNC's controller refuses), or off mid-program:
  /// taxopt switches it per operation itself.
  void check_no_tcp_switch(const toml::table& g, const ProgramTemplate& t) const {
    std::set<std::string> switch_words;
    for (const auto* list : {&t.tcp_on, &t.tcp_off}) {
      for (const std::string& b : *list) {
        std::istringstream words(b);
        for (std::string w; words >> w;) switch_words.insert(w);
      }
    }
    for (const char* key : {"header", "footer", "tool_change"}) {
      const toml::node* n = g.get(key);
      if (!n || !n->is_array()) continue;
      for (const toml::node& e : *n->as_array()) {
        std::istringstream words(e.value<std::string>().value_or(""));
        for (std::string w; words >> w;) {
          if (switch_words.count(w)) {
            fail(line_of(e), std::string("gcode.") + key + " holds " + w +
                                 ", the machine's TCP switch (gcode.tcp_on / tcp_off): taxopt "
                                 "turns TCP on per operation, after the table turn and the tool "
                                 "length, and off before the next");
          }
        }
      }
    }
  }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(source_, line, what);
  }

  void check_keys(const toml::table& t, const std::string& where,
                  const std::set<std::string>& allowed) const {
    for (const auto& [key, node] : t) {
      if (!allowed.count(std::string(key.str()))) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        const std::string full =
            where.empty() ? std::string(key.str()) : where + "." + std::string(key.str());
        fail(line_of(node), "unknown key '" + full + "' (expected one of: " + list + ")");
      }
    }
  }

  const toml::table* table_of(const toml::table& t, const std::string& key, bool required,
                              const std::string& prefix = "") const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(0, "missing section [" + prefix + key + "]");
      return nullptr;
    }
    if (!n->is_table()) fail(line_of(*n), "'" + prefix + key + "' must be a table");
    return n->as_table();
  }

  int whole(const toml::node& n, const std::string& what, int lo, int hi,
            const std::string& why) const {
    // Test the type first: toml++'s value<int64_t>() converts a float, with undefined
    // behaviour when it does not fit (fuzz_machine_file found sense = 6e58).
    const int64_t v = n.is_integer() ? n.as_integer()->get() : lo - 1;
    if (v < lo || v > hi) {
      fail(line_of(n), what + " must be a whole number from " + std::to_string(lo) + " to " +
                           std::to_string(hi) + why);
    }
    return static_cast<int>(v);
  }

  /// A block of the program template, checked by what it does (template_block_problem).
  void check_block(const toml::node& n, const std::string& block, const std::string& what,
                   GcodeDialect dialect, bool footer = false) const {
    const std::string why = template_block_problem(block, what, dialect, footer);
    if (!why.empty()) fail(line_of(n), what + ": '" + block + "' " + why);
  }

  std::string string_of(const toml::node& n, const std::string& what) const {
    if (!n.is_string()) fail(line_of(n), what + " must be a string");
    return n.value<std::string>().value();
  }

  /// Sets `out` from the string key `key` of `table` (section `section`) when it is there:
  /// one of `choices`, else an error listing them.
  template <typename Enum>
  void choose(const toml::table& table, const std::string& section, const std::string& key,
              const std::vector<std::pair<std::string, Enum>>& choices, Enum& out) const {
    const toml::node* n = table.get(key);
    if (!n) return;
    const std::string what = section + "." + key;
    const std::string v = string_of(*n, what);
    std::string list;
    for (std::size_t i = 0; i < choices.size(); ++i) {
      if (v == choices[i].first) {
        out = choices[i].second;
        return;
      }
      list += (i == 0                    ? ""
               : i + 1 == choices.size() ? " or "
                                         : ", ") +
              ("\"" + choices[i].first + "\"");
    }
    fail(line_of(*n), what + " must be " + list + ", got '" + v + "'");
  }

  double number_of(const toml::node& n, const std::string& what) const {
    if (!n.is_number()) fail(line_of(n), what + " must be a number");
    // Read integers and floats explicitly: toml++'s value<double>() is empty for an integer
    // that a double cannot hold exactly (found by fuzz_machine_file).
    const double v =
        n.is_integer() ? static_cast<double>(n.as_integer()->get()) : n.as_floating_point()->get();
    if (!std::isfinite(v)) fail(line_of(n), what + " must be finite");
    return v;
  }

  double number_or(const toml::table& t, const std::string& where, const std::string& key,
                   double fallback) const {
    const toml::node* n = t.get(key);
    return n ? number_of(*n, where + "." + key) : fallback;
  }

  /// A length of the machine (a pivot, a retract height): within 10 m of its origin.
  double length_or(const toml::table& t, const std::string& where, const std::string& key,
                   double fallback) const {
    const double v = number_or(t, where, key, fallback);
    if (!(std::abs(v) <= 1e4)) {
      fail(line_of(*t.get(key)), where + "." + key + " must be within [-1e4, 1e4] mm (a machine)");
    }
    return v;
  }

  void parse_axis(const toml::table& t, const std::string& where, RotaryAxis<double>& axis,
                  bool is_c) const {
    check_keys(t, where,
               {"min_deg", "max_deg", "continuous", "sense", "max_velocity_deg_s",
                "max_accel_deg_s2", "max_jerk_deg_s3", "joint_max_accel_deg_s2"});
    const int line = line_of(t);
    axis = RotaryAxis<double>{};
    if (const toml::node* n = t.get("continuous")) {
      if (!n->is_boolean()) fail(line_of(*n), where + ".continuous must be true or false");
      axis.continuous = n->value<bool>().value();
      if (axis.continuous && !is_c) fail(line_of(*n), "only the C axis can be continuous");
    }
    const toml::node* lo = t.get("min_deg");
    const toml::node* hi = t.get("max_deg");
    if (axis.continuous) {
      if (lo || hi) fail(line, where + ": a continuous axis takes no min_deg/max_deg");
    } else {
      if (!lo || !hi) {
        fail(line, where + " needs min_deg and max_deg" + (is_c ? " (or continuous = true)" : ""));
      }
      const double min_deg = number_of(*lo, where + ".min_deg");
      const double max_deg = number_of(*hi, where + ".max_deg");
      if (!(min_deg < max_deg)) {
        fail(line_of(*lo), where + ": min_deg must be less than max_deg");
      }
      if (!is_c && (min_deg < -360.0 || max_deg > 360.0)) {
        fail(line_of(*lo), where + ": range must lie within [-360, 360] deg");
      }
      // A bounded C of many turns (LinuxCNC's sample: +-36000 deg, 100 turns) is real; beyond
      // 1e5 deg (278 turns) the winding plans outgrow memory and time (tests/test_bad_input.cpp).
      if (is_c && (min_deg < -1e5 || max_deg > 1e5)) {
        fail(line_of(*lo), where + ": range must lie within [-1e5, 1e5] deg (278 turns)");
      }
      axis.min_rad = deg_to_rad(min_deg);
      axis.max_rad = deg_to_rad(max_deg);
    }
    if (const toml::node* n = t.get("sense")) {
      const int64_t v = n->is_integer() ? n->as_integer()->get() : 0;  // type first, as above
      if (v != 1 && v != -1) fail(line_of(*n), where + ".sense must be 1 or -1");
      axis.sense = static_cast<int>(v);
    }
  }

  /// The optional max_velocity_<unit>_s, max_accel_<unit>_s2 and max_jerk_<unit>_s3 of an axis,
  /// and its joint's joint_max_accel_<unit>_s2 (Machine::joint_max_accel_per_s2).
  void parse_limits(const toml::table& t, const std::string& where, const std::string& unit,
                    Machine& m, Joint joint) const {
    const std::size_t j = static_cast<std::size_t>(joint);
    JointLimit& limit = m.limits[j];
    const std::pair<std::string, double*> keys[] = {
        {"max_velocity_" + unit + "_s", &limit.max_velocity_per_s},
        {"max_accel_" + unit + "_s2", &limit.max_accel_per_s2},
        {"max_jerk_" + unit + "_s3", &limit.max_jerk_per_s3},
        {"joint_max_accel_" + unit + "_s2", &m.joint_max_accel_per_s2[j]}};
    for (const auto& [key, value] : keys) {
      if (const toml::node* n = t.get(key)) {
        const double v = number_of(*n, where + "." + key);
        if (!(v > 0.0)) fail(line_of(*n), where + "." + key + " must be positive");
        *value = v;
      }
    }
  }

  std::string source_;
};

}  // namespace

Machine parse_machine_toml(const std::string& text, const std::string& source) {
  return MachineParser(source).parse(text);
}

Machine read_machine_file(const std::string& path) {
  // A machine file is a few kB.
  return parse_machine_toml(
      detail::read_input_file(path, std::uintmax_t{16} << 20, "a machine file", "machine file",
                              "larger than 16 MB: not a machine file"),
      path);
}

}  // namespace taxopt
