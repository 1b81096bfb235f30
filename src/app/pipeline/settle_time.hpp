#pragma once

// How long a garment's hanging cloth needs to come to rest, for the default duration of a drape
// (docs/simulator.md, "Step control and at rest").

namespace sd::app {

// Linear air drag that would damp a garment's swing as still air does, kg/(m²·s) (f = −c·A·v per
// vertex): ½·ρ_air·C_d·v² per square metre across the cloth (ρ_air 1.2 kg/m³, C_d ≈ 1.2 for a
// plate broadside) loses over a swing of speed amplitude V what a linear drag of
// (8/3π)·½·ρ_air·C_d·V ≈ 0.6·V does: 0.1 at the 10-20 cm/s of a hem settling after the drop.
// Garments are NOT given it (docs/simulator.md, "Long garments and the default duration"): it
// lets long skirts rest a second or more sooner but moved three designs of the corpus into
// body-contact cycles that do not end; it is here for the settle-time model and its tests.
inline constexpr double kStillAirDrag = 0.1;

// The longest default duration of a garment's drape, s: the settle time below, without drag,
// is 13-35 s for garments of 0.5-1.4 m, and a drape caught in a contact cycle runs it all.
inline constexpr double kMaxSettleDuration = 10.0;

// The default duration of a garment with a gathered panel (cloth_scene.hpp, gathered), s: its
// flutes settle by slipping over each other and the body, in bursts, long after any swing has
// died, and no pendulum describes that. Measured (one thread): trial 39's gathered skirt (cotton,
// weft 1.6, no duration; not at rest at the 10 s cap, 3.1 cm/s) rests at 12.31 s on a tree
// carrying an unlanded body-vertex push (docs/benchmarks.md, "Round 40"; 15.35 s on round 39's
// binary), the dirndl reproducer at weft 1.8 at 21.65 s;
// trial 37's flounce at weft 1.6 rested at 14.07 s. 30 s covers them with room, and a gathered
// drape caught in a cycle still stops (docs/simulator.md, "Long garments and the default
// duration").
inline constexpr double kGatheredSettleDuration = 30.0;

// The time a cloth hanging over `length` metres needs for a swing to decay from `start_speed`
// to `rest_speed` (m/s): a uniform sheet swinging from its top edge is a pendulum with
// ω² = 3g/(2L); its amplitude decays at γ = c/(2ρ) from the air drag c over the areal density ρ
// (kg/m²), plus ω²·h/2 from implicit Euler's numerical damping at step h (s), so the time is
// ln(start_speed/rest_speed)/γ, plus `fall` seconds for the drop onto the body.
struct SettleInput {
  double length = 1.0;            // m, the garment's extent along gravity
  double area_density = 0.15;     // kg/m²
  double air_drag = 0.0;          // kg/(m²·s), the simulation's (none for garments)
  double time_step = 1.0 / 60.0;  // s
  double gravity = 9.81;          // m/s²
  double start_speed = 0.1;       // m/s, a hem's swing after the drop (measured 7-20 cm/s at 1 s)
  double rest_speed = 5.0e-3;     // m/s
  double fall = 1.0;              // s
};

// Seconds; infinite when nothing damps the swing (no drag and no step).
double settle_time(const SettleInput& in);

}  // namespace sd::app
