#pragma once

// How long a garment's hanging cloth needs to come to rest, for the default duration of a drape
// (docs/simulator.md, "Step control and at rest").

namespace sd::app {

// Linear air drag on garments, kg/(m²·s) (f = −c·A·v per vertex). Still air resists a sheet
// moving across itself with ½·ρ_air·C_d·v² per square metre (ρ_air 1.2 kg/m³, C_d ≈ 1.2 for a
// plate broadside); over a swing of speed amplitude V that loses the energy of a linear drag of
// (8/3π)·½·ρ_air·C_d·V ≈ 0.6·V, so 0.1 at the 10-20 cm/s of a hem settling after the drop. The
// model has no other damping of a swing: its stretch and bending damping act on strain rates, and
// a hem swinging as a pendulum barely strains. 0.1 also stands for the fabric's bending
// hysteresis (KES 2HB), which real cloth has and the model does not.
inline constexpr double kGarmentAirDrag = 0.1;

// The time a cloth hanging over `length` metres needs for a swing to decay from `start_speed`
// to `rest_speed` (m/s): a uniform sheet swinging from its top edge is a pendulum with
// ω² = 3g/(2L); its amplitude decays at γ = c/(2ρ) from the air drag c over the areal density ρ
// (kg/m²), plus ω²·h/2 from implicit Euler's numerical damping at step h (s), so the time is
// ln(start_speed/rest_speed)/γ, plus `fall` seconds for the drop onto the body.
struct SettleInput {
  double length = 1.0;         // m, the garment's extent along gravity
  double area_density = 0.15;  // kg/m²
  double air_drag = kGarmentAirDrag;
  double time_step = 1.0 / 60.0;  // s
  double gravity = 9.81;          // m/s²
  double start_speed = 0.1;       // m/s, a hem's swing after the drop (measured 7-20 cm/s at 1 s)
  double rest_speed = 5.0e-3;     // m/s
  double fall = 1.0;              // s
};

// Seconds; infinite when nothing damps the swing (no drag and no step).
double settle_time(const SettleInput& in);

}  // namespace sd::app
