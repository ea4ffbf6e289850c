// Any input: a machine or an InputError, nothing else. A machine the file accepts, with its
// program template, writes a program that taxopt's reader of its dialect reads back, every
// template block stepped over and the tool, spindle and coolant as written.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/gcode.hpp"
#include "taxopt/io/machine_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  taxopt::Machine m;
  try {
    m = taxopt::parse_machine_toml(std::string(reinterpret_cast<const char*>(data), size),
                                   "fuzz.toml");
  } catch (const taxopt::InputError&) {
    return 0;
  }
  taxopt::PostedOperation op;
  op.name = "F";
  op.tool.number = 3;
  op.spindle_rpm = 1000.0;
  for (int i = 0; i < 3; ++i) {
    taxopt::CLPointd p;
    p.tip_mm = taxopt::Vec3d(5.0 * i, 1.0, 2.0);
    p.axis = taxopt::Vec3d::UnitZ();
    p.motion = i == 0 ? taxopt::Motion::Rapid : taxopt::Motion::Feed;
    p.feed_mm_per_min = i == 0 ? 0.0 : 500.0;
    op.points.push_back(p);
    op.poses.push_back(taxopt::Posed{0.0, 0.0});
  }
  taxopt::GcodeProgram prog;
  try {
    prog = taxopt::write_gcode({op}, m, taxopt::LengthUnit::Millimetre, {"fuzz"});
  } catch (const std::invalid_argument&) {
    return 0;  // a writer precondition (a pose outside a bounded range, ...): not the file's
  }
  const auto moves =
      taxopt::read_gcode_moves(prog.text, "fuzz program", m.gcode.dialect, prog.verbatim_lines,
                               m.rotary.tilt_letter(), prog.tool_calls);
  for (const auto& g : moves) {
    if (!g.rapid && (!g.spindle_on || g.tool != 3)) __builtin_trap();
  }
  return 0;
}
