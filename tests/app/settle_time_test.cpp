// The default duration of a garment's drape: the time a hanging sheet's swing needs to decay to
// the rest speed, checked against the pendulum it models integrated with implicit Euler.

#include "src/app/pipeline/settle_time.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sd::app {
namespace {

// θ̈ + (c/ρ)·θ̇ + ω²·θ = 0 (ω² = 3g/2L) stepped with implicit Euler at h, started at the swing
// speed; the time at which the speed amplitude sqrt(v² + ω²θ²) falls below the rest speed.
double simulated_decay_time(const SettleInput& in) {
  const double w2 = 1.5 * in.gravity / in.length;
  const double k = in.air_drag / in.area_density;
  const double h = in.time_step;
  double theta = 0.0, v = in.start_speed, t = 0.0;
  while (std::sqrt(v * v + w2 * theta * theta) >= in.rest_speed && t < 1000.0) {
    // (1 + h·k)·v' = v − h·ω²·θ' with θ' = θ + h·v'.
    const double v_next = (v - h * w2 * theta) / (1.0 + h * k + h * h * w2);
    theta += h * v_next;
    v = v_next;
    t += h;
  }
  return t;
}

TEST(SettleTime, MatchesTheDampedPendulumItModels) {
  // A 1 m cotton skirt, a 1.35 m jersey maxi dress, a 0.6 m top; the numerical damping alone.
  for (const auto& [length, density, drag] :
       {std::tuple{1.0, 0.13, kStillAirDrag}, std::tuple{1.35, 0.18, kStillAirDrag},
        std::tuple{0.6, 0.13, kStillAirDrag}, std::tuple{1.0, 0.13, 0.0}}) {
    SettleInput in;
    in.length = length;
    in.area_density = density;
    in.air_drag = drag;
    // The energy of a damped oscillator falls in steps within a period (2π/ω ≤ 1.7 s here):
    // within a quarter period of the envelope's time, and 5 % for ωh ≪ 1 (ωh ≤ 0.08).
    const double period = 2 * M_PI / std::sqrt(1.5 * in.gravity / in.length);
    EXPECT_NEAR(settle_time(in) - in.fall, simulated_decay_time(in),
                0.05 * simulated_decay_time(in) + period / 4)
        << length << " m, " << density << " kg/m², drag " << drag;
  }
}

TEST(SettleTime, LongerForLongerLighterAndUndampedCloth) {
  SettleInput in;
  in.air_drag = kStillAirDrag;
  const double base = settle_time(in);
  SettleInput longer = in;
  longer.length = 2 * in.length;  // less numerical damping (ω² ∝ 1/L)
  EXPECT_GT(settle_time(longer), base);
  SettleInput lighter = in;
  lighter.area_density = in.area_density / 2;  // the same drag damps it faster
  EXPECT_LT(settle_time(lighter), base);
  SettleInput still = in;
  still.air_drag = 0.0;
  still.time_step = 0.0;
  EXPECT_EQ(settle_time(still), std::numeric_limits<double>::infinity());
  // 1 m of cotton at 1/60 s: γ = 0.1/0.26 + 14.7·(1/60)/2 = 0.507 /s, ln 20 / γ + 1 = 6.9 s.
  SettleInput cotton;
  cotton.area_density = 0.13;
  cotton.air_drag = kStillAirDrag;
  EXPECT_NEAR(settle_time(cotton), 1.0 + std::log(20.0) / (0.1 / 0.26 + 0.75 * 9.81 / 60), 1e-12);
  EXPECT_NEAR(settle_time(cotton), 6.9, 0.05);
}

}  // namespace
}  // namespace sd::app
