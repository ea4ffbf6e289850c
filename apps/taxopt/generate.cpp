// taxopt generate: the CL file and part mesh of a built-in surface (the paper's sine, a plane,
// a bump, a saddle), its options bounded before anything is allocated.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "cli.hpp"
#include "taxopt/geometry/contact.hpp"
#include "taxopt/geometry/part.hpp"
#include "taxopt/geometry/surface.hpp"
#include "taxopt/io/atomic_file.hpp"
#include "taxopt/io/cl_file.hpp"
#include "taxopt/io/mesh_file.hpp"

namespace taxopt::cli {

std::string data_dir(const char* argv0) {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TAXOPT_DATA_DIR")) return env;
  std::error_code ec;
  const fs::path exe = fs::canonical("/proc/self/exe", ec);
  const fs::path installed =
      (ec ? fs::path(argv0) : exe).parent_path() / ".." / "share" / "taxopt" / "data";
  if (fs::exists(installed / "demo", ec)) return installed.string();
  return TAXOPT_SOURCE_DATA_DIR;
}

namespace {

/// The sine's or the bump's least concave radius, mm, where the path meets it, against the
/// ball's: a surface the ball cannot follow is refused before its raster is made (the raster
/// samples the surface to the chord error, and --wavelength 0.0001 asked for 5.7 GB of points
/// before the gouge was found among them). Empty when the ball fits.
std::string concave_refusal(const GenerateArgs& g) {
  const double pi = Constants<double>::pi();
  double radius_mm = std::numeric_limits<double>::infinity();
  if (g.surface == "sine" && g.length_mm >= g.wavelength_mm) {
    // z = h sin(2 pi y / L): at a trough the curvature is h (2 pi / L)^2.
    const double k = 2.0 * pi / g.wavelength_mm;
    radius_mm = 1.0 / (g.height_mm * k * k);
  } else if (g.surface == "bump") {
    // z = h exp(-r^2 / 2 s^2), s = L / 4: concave beyond r = s, most at r = sqrt(3) s, where
    // the curvature is 2 h exp(-3/2) / s^2; inside the path's rectangle when that ring is.
    const double s = g.wavelength_mm / 4.0;
    if (std::sqrt(3.0) * s < 0.5 * std::min(g.width_mm, g.length_mm)) {
      radius_mm = s * s / (2.0 * g.height_mm * std::exp(-1.5));
    }
  }
  if (!(radius_mm < g.raster.tool_radius_mm)) return {};
  std::ostringstream os;
  os << "generate: the " << g.surface << "'s least concave radius is " << radius_mm
     << " mm, below the tool radius " << g.raster.tool_radius_mm
     << " mm: the ball would gouge (eq. 19); use a longer wavelength, a lower height or a "
        "smaller tool";
  return os.str();
}

/// The options checked before anything is allocated: the outputs, each number within what a
/// part and a machine are, the memory the mesh and the raster take. 0, else the exit code.
int generate_refusal(const GenerateArgs& g) {
  if (g.out_cls.empty() && g.out_mesh.empty())
    return error("generate: give --out-cls and/or --out-mesh", 2);
  if (g.surface != "sine" && g.surface != "plane" && g.surface != "bump" && g.surface != "saddle") {
    return error("generate: --surface must be sine, plane, bump or saddle", 2);
  }
  // The outputs checked as the main job's are: not one file twice, nowhere they cannot be
  // written (a FIFO, a read-only file, a device).
  if (!g.out_cls.empty() && !g.out_mesh.empty() && same_file(g.out_cls, g.out_mesh)) {
    return error("generate: --out-cls and --out-mesh name the same file " + g.out_cls, 2);
  }
  for (const auto& [opt, path] : {std::make_pair(std::string("--out-cls"), g.out_cls),
                                  std::make_pair(std::string("--out-mesh"), g.out_mesh)}) {
    if (path.empty()) continue;
    if (const std::string why = writable_output_problem(path); !why.empty()) {
      return error("generate: " + opt + " " + path + ": cannot write there: " + why, 2);
    }
  }
  // Each option within what a part and a machine are (and NaN never): a bound with a reason,
  // checked before anything is allocated (tests/test_bad_input.cpp).
  struct Bound {
    const char* name;
    double value, lo, hi;
    bool lo_open;
    const char* why;
  };
  const Bound bounds[] = {
      {"--height", g.height_mm, 0.0, 500.0, true, "mm: a part on a machine table"},
      {"--wavelength", g.wavelength_mm, 0.0, 2000.0, true, "mm"},
      {"--width", g.width_mm, 0.0, 2000.0, true, "mm: a machine's travel"},
      {"--length", g.length_mm, 0.0, 2000.0, true, "mm: a machine's travel"},
      {"--mesh-step", g.mesh_step_mm, 0.05, 50.0, false, "mm"},
      {"--feed", g.feed_mm_per_min, 0.01, 1e6, false, "mm/min"},
      {"--spindle", g.spindle_rpm, 0.0, 1e6, false, "rpm"},
      {"--tool-radius", g.raster.tool_radius_mm, 0.0, 100.0, true, "mm"},
      {"--scallop", g.raster.scallop_mm, 1e-4, 10.0, false, "mm"},
      {"--chord-error", g.raster.chord_error_mm, 1e-4, 10.0, false, "mm"},
      {"--tilt", g.raster.tilt_deg, -89.0, 89.0, false, "deg: the tool stays above the surface"},
      {"--yaw", g.raster.yaw_deg, -360.0, 360.0, false, "deg"},
  };
  for (const Bound& b : bounds) {
    const bool ok = (b.lo_open ? b.value > b.lo : b.value >= b.lo) && b.value <= b.hi;
    if (!ok) {
      std::ostringstream os;
      os << "generate: " << b.name << " must be within " << (b.lo_open ? "(" : "[") << b.lo << ", "
         << b.hi << "] " << b.why;
      return error(os.str(), 2);
    }
  }
  if (const std::string why = concave_refusal(g); !why.empty()) return error(why, 2);
  // Memory before allocating: the mesh's cells and the raster's points.
  const double reach = 2.0 * 4.0 * g.raster.tool_radius_mm;
  const double cells_budget = ((g.width_mm + reach) / g.mesh_step_mm + 1.0) *
                              ((g.length_mm + reach) / g.mesh_step_mm + 1.0);
  const double passes =
      g.width_mm / std::max(std::sqrt(8.0 * g.raster.tool_radius_mm * g.raster.scallop_mm), 1e-9);
  const double per_pass =
      g.length_mm / std::min(g.raster.max_step_mm,
                             std::sqrt(8.0 * g.raster.tool_radius_mm * g.raster.chord_error_mm));
  if (cells_budget > 5e6 || passes * per_pass > 5e6) {
    return error(
        "generate: more than 2e7 mesh cells or CL points (a budget of about 2 GB); "
        "coarsen --mesh-step, --scallop or --chord-error, or shrink --width/--length",
        2);
  }
  return 0;
}

/// How far the mesh lies off `surface`, mm: the largest |facet - surface| along the surface's
/// normal at points of every facet (its corners, edges' and inner points at quarters), for a
/// surface over x, y (z = f(x, y)). A ball resting on the surface cuts a facet above it by up
/// to this, or floats over one below it.
template <class Surface>
double mesh_deviation_mm(const Surface& surface, const TriangleMesh& mesh) {
  constexpr int kSteps = 4;
  double deviation = 0.0;
  for (const auto& f : mesh.faces) {
    const Vec3d& a = mesh.vertices[static_cast<std::size_t>(f[0])];
    const Vec3d& b = mesh.vertices[static_cast<std::size_t>(f[1])];
    const Vec3d& c = mesh.vertices[static_cast<std::size_t>(f[2])];
    for (int i = 0; i <= kSteps; ++i) {
      for (int k = 0; i + k <= kSteps; ++k) {
        const Vec3d p = a + (b - a) * (double(i) / kSteps) + (c - a) * (double(k) / kSteps);
        const auto j = surface.jet(p.x(), p.y());
        Vec3d n = j.su.cross(j.sv).normalized();
        if (n.z() < 0.0) n = -n;
        deviation = std::max(deviation, std::abs((p - j.p).dot(n)));
      }
    }
  }
  return deviation;
}

/// The raster of CL points over the chosen surface, and the surface's mesh over the domain grown
/// by the tool's reach (so that a tool at the path's edge still sees the part around it).
void raster_and_mesh(const GenerateArgs& g, std::vector<GeneratedPoint>& pts, TriangleMesh& mesh,
                     double& deviation_mm) {
  deviation_mm = 0.0;  // a plane's mesh is the plane
  const double margin = 4.0 * g.raster.tool_radius_mm;
  const auto cells = [&](double size) {
    return std::max(1, static_cast<int>(std::ceil(size / g.mesh_step_mm)));
  };
  // The raster over a surface on x, y, and its mesh over the domain grown by the margin.
  const auto over = [&](const auto& surface) {
    pts = generate_raster(surface, g.raster);
    auto big = surface;
    big.x0_mm -= margin, big.x1_mm += margin, big.y0_mm -= margin, big.y1_mm += margin;
    mesh = tessellate(big, cells(big.x1_mm - big.x0_mm), cells(big.y1_mm - big.y0_mm));
    deviation_mm = mesh_deviation_mm(big, mesh);
  };
  if (g.surface == "sine") {
    SineSurfaced sine;
    sine.height_mm = g.height_mm;
    sine.wavelength_mm = g.wavelength_mm;
    sine.x1_mm = g.width_mm;
    sine.y1_mm = g.length_mm;
    over(sine);
  } else if (g.surface == "bump" || g.surface == "saddle") {
    // Centred on the path's rectangle: the bump's sigma a quarter of --wavelength, the
    // saddle's half-widths the rectangle's; both --height high.
    const auto heightfield = [&](auto field) {
      over(HeightfieldSurface<double, decltype(field)>{{0.0, g.width_mm, 0.0, g.length_mm}, field});
    };
    if (g.surface == "bump") {
      heightfield(BumpField<double>{g.height_mm, g.wavelength_mm / 4.0, g.width_mm / 2.0,
                                    g.length_mm / 2.0});
    } else {
      heightfield(SaddleField<double>{g.height_mm, g.width_mm / 2.0, g.length_mm / 2.0,
                                      g.width_mm / 2.0, g.length_mm / 2.0});
    }
  } else {
    Planed plane;
    plane.u_size_mm = g.width_mm;
    plane.v_size_mm = g.length_mm;
    pts = generate_raster(plane, g.raster);
    Planed big = plane;
    big.origin = Vec3d(-margin, -margin, 0.0);
    big.u_size_mm += 2 * margin, big.v_size_mm += 2 * margin;
    mesh = tessellate(big, cells(big.u_size_mm), cells(big.v_size_mm));
  }
}

/// The generated points as one operation of a ball-end tool at the job's feed and spindle.
Operationd generated_operation(const GenerateArgs& g, const std::vector<GeneratedPoint>& pts) {
  Operationd op;
  // Named after its surface (SINE_FINISH, BUMP_FINISH, ...): a bump's was PLANE_FINISH.
  op.name = g.surface + "_FINISH";
  for (char& ch : op.name) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  op.tool = Tool::ball_end_mill(2 * g.raster.tool_radius_mm, 5 * g.raster.tool_radius_mm);
  op.tool.name =
      "BALL_MILL_D" + std::to_string(static_cast<int>(std::lround(2 * g.raster.tool_radius_mm)));
  op.tool.number = 1;
  op.spindle_rpm = g.spindle_rpm;
  for (const auto& p : pts) {
    CLPointd c;
    c.tip_mm = p.tip_mm;
    c.axis = p.axis;
    c.motion = p.rapid ? Motion::Rapid : Motion::Feed;
    c.feed_mm_per_min = p.rapid ? 0.0 : g.feed_mm_per_min;
    op.points.push_back(c);
  }
  return op;
}

/// Why the mesh cannot stand for the surface the points were made on ("" when it can): where
/// it lies farther off the surface than the post's least contact tolerance, the post's own
/// contact check on the pair -- a ball cutting the mesh beyond the tolerance the post takes
/// for it, or most balls off it (a --mesh-step of 50 mm wrote a pair the post refused).
std::string coarse_mesh_refusal(const GenerateArgs& g, const std::vector<GeneratedPoint>& pts,
                                const TriangleMesh& mesh, double deviation_mm) {
  if (deviation_mm <= kContactToleranceFloorMm) return "";
  const Part part(mesh);
  const double tolerance_mm = contact_tolerance_mm(part, ContactOptions{});
  const double r = g.raster.tool_radius_mm;
  double deepest_mm = 0.0;
  std::size_t feed = 0, touching = 0;
  for (const GeneratedPoint& p : pts) {
    if (p.rapid) continue;
    const double gap_mm = part.closest(Vec3d(p.tip_mm + r * p.axis)).distance_mm - r;
    ++feed;
    touching += std::abs(gap_mm) <= tolerance_mm;
    deepest_mm = std::max(deepest_mm, -gap_mm);
  }
  if (deepest_mm <= tolerance_mm && 10 * touching >= 9 * feed) return "";
  std::ostringstream os;
  os << "generate: the mesh at --mesh-step " << g.mesh_step_mm << " mm lies up to " << deviation_mm
     << " mm off the surface: a ball on the surface cuts it " << deepest_mm << " mm, "
     << feed - touching << " of " << feed
     << " feed points are off it, against the post's contact tolerance " << tolerance_mm
     << " mm for this mesh; a finer --mesh-step (the deviation falls with its square: about "
     << g.mesh_step_mm * std::sqrt(kContactToleranceFloorMm / deviation_mm)
     << " mm keeps it within " << kContactToleranceFloorMm << " mm)";
  return os.str();
}

}  // namespace

int run_generate(const GenerateArgs& g) {
  if (const int code = generate_refusal(g)) return code;
  std::vector<GeneratedPoint> pts;
  TriangleMesh mesh;
  double deviation_mm = 0.0;
  try {
    raster_and_mesh(g, pts, mesh, deviation_mm);
  } catch (const std::invalid_argument& e) {
    return error(std::string("generate: ") + e.what(), 2);
  }
  const std::size_t gouging = static_cast<std::size_t>(
      std::count_if(pts.begin(), pts.end(), [](const GeneratedPoint& p) { return p.gouges; }));
  if (gouging) {
    return error(
        "generate: " + std::to_string(gouging) +
            " contact points have a concave radius below the tool radius: the ball "
            "would gouge (eq. 19); use a longer wavelength, a lower height or a smaller tool",
        2);
  }
  if (const std::string why = coarse_mesh_refusal(g, pts, mesh, deviation_mm); !why.empty()) {
    return error(why, 2);
  }
  const Operationd op = generated_operation(g, pts);
  OutputTransaction tx;
  if (!g.out_cls.empty()) tx.stage(g.out_cls, format_new_cl({op}));
  if (!g.out_mesh.empty())
    tx.stage(g.out_mesh, format_stl_binary(mesh, "taxopt generate " + g.surface));
  tx.commit();
  return 0;
}

}  // namespace taxopt::cli
