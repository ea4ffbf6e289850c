#pragma once
// The real-job harness's part and CL file (tests/test_real_job.cpp): the classes of operations
// of the Haas UMC-750 course job (docs/results.md), made again on a CAD-style part of our own.
// The part: a round boss with a fillet at its foot on a floor that falls away as a cone; an oval
// boss whose wall overhangs its fillet (an undercut); a bar with a chamfer down one edge; a block
// of rounded corners with a chamfer round its top. Eight operations, as a CAM system writes them
// (NX CLSF, mm, a 6 mm ball, 800 mm/min):
// - CHAMFER: along the bar's straight chamfer at a constant axis (a 10 deg lead): nothing to gain;
// - OUTLINE_CHAMFER: round the block's chamfer at a 10 deg lead: the tilt still, C turning a
//   quarter round each corner;
// - ROTARY_FLOOR: 4-axis, round the cone at a constant tilt, C turning evenly;
// - FILLET: along the round boss's fillet, the tool near upright (leaning off the boss 0.5 to
//   3.5 deg as an interpolated axis wavers), its side 0.04 to 0.2 mm off the part: a turn toward
//   the boss puts the flutes into it;
// - CURVE_FILLET: round the oval boss's undercut fillet, leaning out 12 to 16 deg (the wall
//   overhangs at 12), C fast round the ends: a lean of less reaches into the wall;
// - OVAL, OVAL_OPPOSITE, CIRCLE: loops on the floor at a 15 deg lead or side tilt, C following
//   the path's direction.
#include <string>

#include "taxopt/geometry/triangle_mesh.hpp"

namespace taxopt::test {

/// The tool of every operation: its ball radius and flute length, mm.
constexpr double kRealJobBallMm = 3.0;
constexpr double kRealJobFluteMm = 20.0;

/// The part's mesh (closed components, outward normals).
TriangleMesh real_job_part();
/// The CL file of its eight operations.
std::string real_job_cl();

}  // namespace taxopt::test
