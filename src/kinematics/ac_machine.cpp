#include "taxopt/kinematics/ac_machine.hpp"

namespace taxopt {

ACMachined default_ac_machine() {
  ACMachined m;
  m.a.min_rad = deg_to_rad(-120.0);
  m.a.max_rad = deg_to_rad(120.0);
  m.c.continuous = true;
  return m;
}

}  // namespace taxopt
