#include "src/app/pipeline/settle_time.hpp"

#include <cmath>
#include <limits>

namespace sd::app {

double settle_time(const SettleInput& in) {
  const double omega_squared = 1.5 * in.gravity / in.length;
  const double decay = in.air_drag / (2 * in.area_density) + 0.5 * omega_squared * in.time_step;
  if (!(decay > 0.0)) return std::numeric_limits<double>::infinity();
  return in.fall + std::log(in.start_speed / in.rest_speed) / decay;
}

}  // namespace sd::app
