#pragma once
/// @file The cutter as collision checks see it.
///
/// A ball-end mill of radius R with its tip at P and axis V has its ball centre at C = P + R V.
/// The ball touches the part at the contact point by construction (checked by contact recovery
/// and, for concave regions, by the local gouge check of eq. 19), so the checked body is what
/// lies above the ball centre: coaxial cylinders, each from `start_mm` to `end_mm` along V
/// measured from C:
///   flutes  radius R                    from 0            to flute_length - R
///   shank   radius shank_radius         from flute_length - R to gauge_length - R
///   holder  radius holder_radius        from gauge_length - R to gauge_length - R + holder_length
/// (lengths from the tip, as on a tool sheet). For a CL point where the ball is in the air
/// (approach, retract) the ball itself is checked too.

#include <optional>
#include <vector>

#include "taxopt/core/export.hpp"
#include "taxopt/core/toolpath.hpp"

namespace taxopt {

/// A coaxial cylinder of the tool, lengths along the axis from the ball centre.
struct ToolBody {
  double radius_mm = 0.0;
  double start_mm = 0.0;
  double end_mm = 0.0;
};

/// How the collision checks judge each body (docs/cli.md, "What is checked"): the flutes cut,
/// so they may touch the surface they cut within the part's tolerance (the mesh's chordal
/// error): their cylinder is checked that much thinner; the shank past the flutes and the
/// holder never cut: they are checked grown by their clearances (radius, and the holder also
/// towards the tip), so a free verdict keeps them at least that far from the part.
struct ToolMargins {
  double flute_tolerance_mm = 0.0;
  double shank_clearance_mm = 0.0;
  double holder_clearance_mm = 0.0;
};

/// Tool dimensions given on the command line (mm), overriding the CL file's.
struct ToolOverrides {
  std::optional<double> ball_radius_mm, shank_radius_mm, flute_length_mm, holder_radius_mm,
      holder_length_mm, gauge_length_mm;
};

/// The bodies of a ball-end mill.
struct TAXOPT_API ToolModel {
  double ball_radius_mm = 0.0;
  std::vector<ToolBody> bodies;

  /// Farthest distance from the ball centre that any body reaches, mm.
  double reach_mm() const;

  /// Builds the model of a ball-end `tool` with `overrides`. Defaults: flute length from the
  /// file (else 4 diameters), shank radius = R, gauge length = max(flute length, 10 diameters),
  /// no holder unless its radius is given (holder length then defaults to 40 mm).
  /// @throws InputError when the dimensions contradict each other (shank thinner than zero,
  /// gauge length shorter than the flutes, a holder thinner than the shank).
  static ToolModel ball_end(const Tool& tool, const ToolOverrides& overrides = {});

  /// The bodies above the flutes of a mill that is no ball end (flat, bull nose: diameter D,
  /// corner radius r): the shank (radius D / 2 unless overridden) and the holder, lengths as
  /// in ball_end but measured from the point r above the tip on the axis (ball_radius_mm is
  /// r). No flute body (flute_bodies 0): without a contact model the cutting part is not
  /// judged, but the bodies that never cut are (tests/test_bad_input.cpp).
  /// @throws InputError as ball_end does, and for a tool without a diameter.
  static ToolModel shank_and_holder(const Tool& tool, const ToolOverrides& overrides = {});

  /// The bodies as the collision checks judge them (ToolMargins): the flutes thinner by
  /// their tolerance (never below half the ball radius), the shank and holder grown.
  ToolModel judged(const ToolMargins& margins) const;

  /// Number of leading bodies that are flutes (0 or 1).
  int flute_bodies = 1;
  /// Index of the holder body, -1 when there is none.
  int holder_body = -1;
};

}  // namespace taxopt
