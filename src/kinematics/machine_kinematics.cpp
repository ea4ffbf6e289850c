#include "taxopt/kinematics/machine_kinematics.hpp"

namespace taxopt {

MachineKinematicsd default_machine_kinematics() {
  MachineKinematicsd m;
  m.tilt.min_rad = deg_to_rad(-120.0);
  m.tilt.max_rad = deg_to_rad(120.0);
  m.c.continuous = true;
  return m;
}

}  // namespace taxopt
