// The CL reader's word table (cl_words.hpp). Each entry names the CAM systems
// that write the word and the evidence for what taxopt does with it; docs/cl-files.md shows it.
#include "cl/cl_words.hpp"

#include <algorithm>
#include <iterator>

namespace taxopt {

namespace {

using M = ClWordMeaning;

constexpr const char* kApt = "ANSI X3.37 APT (CL data)";
constexpr const char* kNx = "NX CLSF manual (CLSF Manager)";
constexpr const char* kSw = "tests/data/real amorim-*.apt (SOLIDWORKS CAM)";
constexpr const char* kSubroutine =
    "moves the tool by a body taxopt does not expand: refused (expand it in the CAM system)";

/// The table: data, in the order docs/cl-files.md lists it (one row per word).
constexpr ClWord kWords[] = {
    // Motion.
    {"GOTO", M::Motion, "a point x,y,z[,i,j,k]; 3 numbers keep the axis in force", "all", kApt,
     false},
    {"FROM", M::Motion, "the start point (a rapid move) and the home GOHOME returns to",
     "NX, CATIA, generic APT", kApt, false},
    {"GODLTA", M::Motion, "a move by dx,dy,dz, or by d along the tool axis", "generic APT", kApt,
     false},
    {"GOHOME", M::Motion,
     "a rapid move back to the FROM point and axis; with x,y,z[,i,j,k] (NX's Gohome point) to "
     "that point",
     "CATIA, NX, generic APT", kApt, false},
    {"CIRCLE", M::Motion,
     "an arc to the next GOTO about (i,j,k), in the CAM system's sense, checked against the "
     "tangents of the moves beside it",
     "NX, Makino, CATIA, SOLIDWORKS CAM, Creo",
     "NX CLSF manual (clockwise); tangent continuity on the real files (docs/cl-files.md)", false},
    {"MOVARC", M::Motion,
     "an arc to the next GOTO sweeping ANGLE deg counter-clockwise about (i,j,k), checked "
     "against the GOTO and the tangents of the moves beside it",
     "Autodesk Fusion / HSM",
     "five public Fusion files: 24,948 arcs, tangent continuity 24,483 to 2 "
     "(tests/data/real/SOURCES.md)",
     false},
    {"NURBS", M::Motion, "a rational B-spline from the current point (KNOT and CNTRL follow)", "NX",
     kNx, false},
    {"KNOT", M::Motion, "the knots of the NURBS being read", "NX", kNx, false},
    {"CNTRL", M::Motion, "a control point x,y,z[,w] of the NURBS being read", "NX", kNx, false},
    {"CYCLE", M::Motion,
     "a drilling cycle in keyword form (FEDTO, RAPTO, RTRCTO, pecks): each GOTO is a hole, "
     "expanded into its moves; other forms are refused",
     "NX, SOLIDWORKS CAM", kSw, false},
    // State.
    {"RAPID", M::State, "the next motion is a rapid move", "all", kApt, false},
    {"FEDRAT", M::State, "the feed: a number and at most one unit word (MMPM, IPM, PERMIN, ...)",
     "all", kApt, false},
    {"MULTAX", M::State, "MULTAX/OFF: 3-axis from there on, the axis +Z", "CATIA, NX", kApt, false},
    {"TLAXIS", M::State, "TLAXIS/i,j,k: the tool axis of the 3-number GOTOs after it",
     "CATIA, Creo", kApt, false},
    {"UNITS", M::State, "INCHES or MM, before any motion", "Creo, NX", kApt, false},
    {"UNIT", M::State, "as UNITS", "SOLIDWORKS CAM", kSw, false},
    {"TLDATA", M::State, "TLDATA/MILL,d,r,l: the tool's diameter, corner radius, flute length",
     "NX", kNx, false},
    {"CUTTER", M::State,
     "the tool: APT's d,r,e,f,a,b,h (diameter, corner radius, height); r > d/2 is a tapered "
     "ball mill of taper b where d = 2 r (1 - sin b) / cos b, else refused",
     "CATIA, SOLIDWORKS CAM, generic APT", kApt, false},
    {"LOADTL", M::State,
     "the tool number; OSETNO / ADJUST with the tool's own register, LENGTH (the collision "
     "check's gauge length unless an option or the machine file gives one), IN (the pocket, not "
     "written), or Fusion's t, pocket, length, register by position",
     "CATIA, Creo, Fusion", kApt, false},
    {"TOOLNO", M::Information,
     "TOOLNO/n,d: the tool number and diameter of the LOADTL that follows, checked against it "
     "and the CUTTER (the LOADTL changes the tool)",
     "CATIA",
     "CATIA V5 NC Manufacturing, Import APT Source File (TOOLNO/1, 10.000000 then TPRINT and "
     "LOADTL); tests/data/real/peening-catia-multax.aptsource",
     true},
    {"LOAD", M::State, "LOAD/TOOL,n: the tool number", "NX, SOLIDWORKS CAM", kNx, false},
    {"SPINDL", M::State,
     "speed (RPM, or SFM / SMM turned into rpm through the cutter's diameter), CLW / CCLW, "
     "OFF; a change after motion reaches the program where it stands",
     "all", kApt, false},
    {"SPINDLE", M::State, "as SPINDL", "CATIA", kApt, false},
    {"COOLNT", M::State,
     "ON / FLOOD (M8), MIST (M7), OFF (M9); where it stands; other kinds are refused", "all", kApt,
     false},
    {"INTOL", M::Information,
     "the CAM's inside tolerance, ds[,ps,cs1,cs2] (the part surface's: the second, else the "
     "first): added to the part mesh's chordal error in the default contact tolerance",
     "generic APT, CATIA", kApt, true},
    {"OUTTOL", M::Information,
     "the CAM's outside tolerance: as INTOL (the larger of the two is taken)", "generic APT, CATIA",
     kApt, true},
    {"TOLER", M::Information,
     "a tolerance as OUTTOL (some APT processors take it for the whole band: either way the "
     "band the path may lie off the surface)",
     "generic APT", kApt, true},
    {"CUTCOM", M::State,
     "OFF is taken; LEFT / RIGHT (compensation in the control) are refused: taxopt posts the "
     "tool centre path without G41/G42",
     "SOLIDWORKS CAM, CATIA", kApt, true},
    // Frames.
    {"MSYS", M::Frame,
     "the MCS of the coordinates that follow; they are posted as written (as the production "
     "NX post does), or moved into it with --msys apply",
     "NX", "tests/data/real-post: the NX post for the Haas UMC-750 writes the GOTOs unchanged",
     false},
    // Program.
    {"STOP", M::Program, "a program stop (M0) where it stands", "CATIA, generic APT", kApt, true},
    {"OPSTOP", M::Program, "an optional stop (M1) where it stands", "generic APT", kApt, true},
    {"DELAY", M::Program,
     "DELAY/s: a dwell of s seconds where it stands (LinuxCNC G4 P s, Fanuc G04 P ms); "
     "refused for the other dialects",
     "generic APT", kApt, true},
    {"INSERT", M::Program,
     "a bracketed operator's note (INSERT/[HOLDER=...]) dropped with a note; prose "
     "(INSERT/Stock Size X135. Y135. Z30.) written as a comment where it stands; a program "
     "stop M00 / M01 alone or beside a note (INSERT/M00 (REMOVE CLAMP)) written as STOP / "
     "OPSTOP, the note as a comment before it; a stop or end among other text, and other "
     "address words (INSERT/G54 G90), are refused: taxopt does not pass uninterpreted code "
     "into a program, nor drop a stop (--skip-record INSERT drops every INSERT)",
     "SOLIDWORKS CAM, generic APT", kApt, true},
    // Structure.
    {"TOOL PATH", M::Structure, "opens an operation (its name and tool)", "NX", kNx, false},
    {"END-OF-PATH", M::Structure, "closes the operation", "NX", kNx, false},
    {"FINI", M::Structure, "the end of the file: motion after it is refused", "all", kApt, false},
    {"END", M::Structure, "the end of the program: motion after it is refused", "CATIA", kApt,
     false},
    // Information.
    {"PAINT", M::Information, "display colour of the path", "NX", kNx, true},
    {"PPRINT", M::Information, "operator text", "CATIA, generic APT", kApt, true},
    {"PARTNO", M::Information, "the program's name", "all", kApt, true},
    {"TPRINT", M::Information, "tool text", "CATIA, Creo", kApt, true},
    {"SELECT", M::Information, "SELECT/TOOL,n: the next tool to stage", "SOLIDWORKS CAM", kSw,
     true},
    {"CSYS", M::Information,
     "the setup's frame; the GOTOs are already in world coordinates (each axis is its third "
     "column)",
     "SOLIDWORKS CAM", "tests/data/real/SOURCES.md (every 6-number GOTO)", true},
    {"TRNTYP", M::Information, "the kind of the CSYS that follows", "SOLIDWORKS CAM", kSw, true},
    {"CSI_SET_FLUTE_LENGTH", M::Information, "the tool's flute length (CUTTER gives its height)",
     "SOLIDWORKS CAM", kSw, true},
    {"CSI_SET_EXTENSION_LENGTH", M::Information, "the tool's length out of the holder",
     "SOLIDWORKS CAM", kSw, true},
    {"MACHIN", M::Information,
     "the post-processor's name; a turning machine (MACHIN/...,TURN) is refused", "Creo, CATIA",
     kApt, true},
    {"SET", M::Information,
     "SET/MODE,ABSOL: the coordinates are absolute, as taxopt reads every CL file; "
     "SET/MODE,INCR and every other SET are refused",
     "Makino FFCAM", "steptools/STEPNode examples/data/Plane_2.cldata (Makino FF APT-CL)", false},
    {"MODE", M::Information,
     "MODE/MILL: the machine mills (line 1 of Fusion 360's APT files); MODE/TURN and every "
     "other mode are refused",
     "Fusion 360, CATIA, Pro/E", kApt, false},
    // Refused: they move the tool or its frame, or change what the moves mean.
    {"DEFSUB", M::Refused, kSubroutine, "Pro/E, generic APT", kApt, false},
    {"ENDSUB", M::Refused, kSubroutine, "Pro/E, generic APT", kApt, false},
    {"CALL", M::Refused, kSubroutine, "Pro/E, generic APT", kApt, false},
    {"COPY", M::Refused, kSubroutine, "Pro/E, generic APT", kApt, false},
    {"LOOP", M::Refused,
     "LOOP/START,n ... LOOP/END: the post repeats the body n times (turning between copies)",
     "CATIA", "a shop's CATIA post (LOOP/START, LOOP/END around its copies)", false},
    {"INDEX", M::Refused, "moves the frame", "generic APT", kApt, false},
    {"ROTATE", M::Refused, "turns the frame", "generic APT", kApt, false},
    {"ROTABL", M::Refused, "turns a rotary table", "generic APT", kApt, false},
    {"TRANS", M::Refused, "moves the frame", "generic APT", kApt, false},
    {"ORIGIN", M::Refused, "moves the frame", "generic APT", kApt, false},
    {"REFSYS", M::Refused, "moves the frame", "generic APT", kApt, false},
    {"MIRROR", M::Refused, "mirrors the moves", "generic APT", kApt, false},
    {"INVERSE", M::Refused, "INVERSE/ON: the feeds that follow are not units per minute", "CATIA",
     kApt, false},
    {"OP", M::Refused, "a machining cycle of the post (OP/THREAD ...)", "Pro/E", kApt, false},
    {"TURRET", M::Refused, "a lathe turret: a turning file", "generic APT", kApt, false},
    {"GO", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GOFWD", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GOLFT", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GORGT", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GOBACK", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GOUP", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"GODOWN", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"INDIRV", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"INDIRP", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"PSIS", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"TLON", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"TLLFT", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"TLRGT", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"TLOFPS", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"AUTOPS", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"THICK", M::Refused, "APT part-program motion (not CL data)", "APT source", kApt, false},
    {"ARC", M::Refused, "a curve form taxopt does not evaluate", "generic APT", kApt, false},
    {"SPLINE", M::Refused, "a curve form taxopt does not evaluate", "generic APT", kApt, false},
    {"BSPLIN", M::Refused, "a curve form taxopt does not evaluate", "generic APT", kApt, false},
    {"POLYLN", M::Refused, "a curve form taxopt does not evaluate", "generic APT", kApt, false},
};

}  // namespace

const std::vector<ClWord>& cl_words() {
  static const std::vector<ClWord> words(std::begin(kWords), std::end(kWords));
  return words;
}

const ClWord* find_cl_word(const std::string& major) {
  const auto& w = cl_words();
  const auto it =
      std::find_if(w.begin(), w.end(), [&](const ClWord& e) { return major == e.word; });
  return it == w.end() ? nullptr : &*it;
}

const char* to_string(ClWordMeaning meaning) {
  switch (meaning) {
    case M::Motion: return "motion";
    case M::State: return "state";
    case M::Frame: return "frame";
    case M::Program: return "program";
    case M::Structure: return "structure";
    case M::Information: return "information";
    case M::Refused: return "refused";
  }
  return "?";
}

std::string cl_words_markdown() {
  std::string out =
      "| word | meaning | what taxopt does | written by | evidence | --skip-record |\n"
      "|---|---|---|---|---|---|\n";
  for (const ClWord& w : cl_words()) {
    out += "| `" + std::string(w.word) + "` | " + to_string(w.meaning) + " | " + w.what + " | " +
           w.writers + " | " + w.evidence + " | " + (w.skippable ? "yes" : "no") + " |\n";
  }
  return out;
}

}  // namespace taxopt
