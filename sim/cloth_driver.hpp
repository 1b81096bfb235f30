#pragma once
// The cloth driver: the one way a cloth is draped, on a fixed mesh or with adaptive 4-8 detail.
//
// A cloth given as a 4-8 mesh (a garment's stitched quads, an imported garment's sqrt3 mesh, a
// sheet's quads) is driven by AdaptiveCloth; it adapts only when AdaptiveSettings::enabled, and
// with adaptivity off its mesh stays as built (or as refine_uniformly left it): the fixed mesh is
// the adaptive driver with adaptivity off. A cloth given as a finished model (any triangles: a
// sheet's alternating diagonals, the stress study's slivers) runs on that fixed mesh. Either way
// Simulation::run's loop steps it and fills one report; an observer sees every step.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <vector>

#include "meshing/mesh48.hpp"
#include "meshing/tri_mesh.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/body_motion.hpp"
#include "sim/cloth_model.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

class ClothDriver;

// What a caller does around the steps of ClothDriver::run.
struct ClothObserver {
  // Before every step; may change the mesh (the stress study's forced churn).
  std::function<void(ClothDriver&)> before_step;
  // After every step: an accepted one (the state is the step's end, the mesh adapted, the
  // energy sampled) or the failed one that ends the run. Returning false stops the run there.
  std::function<bool(const ClothDriver&, const StepOutcome&)> after_step;
  // Caps each step (e.g. to land on sample times): the step may not pass time() + this; empty:
  // only the duration caps it.
  std::function<double(const ClothDriver&)> max_step;
};

class ClothDriver {
 public:
  // A fixed mesh: the model as given, x0 its 3n start positions (flatten_positions), and
  // optionally the input face each triangle belongs to (a sheet's quad; empty: each triangle is
  // its own). Throws as Simulation's constructor.
  ClothDriver(ClothModel model, Eigen::VectorXd x0, std::vector<Pin> pins,
              SimulationSettings settings, Eigen::VectorXi source_faces = {});
  // A 4-8 mesh (see AdaptiveCloth's constructor), adapting when adaptive.enabled.
  ClothDriver(meshing::Mesh48 mesh, AdaptiveMaterial material, Eigen::MatrixX3d positions,
              std::vector<Pin> pins, SimulationSettings settings, AdaptiveSettings adaptive);
  ~ClothDriver();
  ClothDriver(ClothDriver&&) noexcept;
  ClothDriver& operator=(ClothDriver&&) noexcept;

  // The body, still or moving (Simulation::set_body, set_body_motion). Call before stepping.
  void set_body(const meshing::TriMesh& body);
  void set_body_motion(PoseSequence motion);
  // Start velocities (3n); a fixed mesh only (an adaptive cloth starts at rest).
  void set_velocities(const Eigen::VectorXd& v);

  // One accepted step (Simulation::step), then the mesh adapts (a 4-8 mesh with adaptivity on).
  StepOutcome step(double max_step = 1e300);
  // Steps until the duration, at rest, failure or the observer's stop; the simulation's report.
  // For a 4-8 mesh, adaptive_report() then holds adaptivity's counts next to it.
  SimulationReport run(const ClothObserver& observer = {});

  const Simulation& simulation() const;
  // The adaptive cloth (a 4-8 mesh, adapting or not); null for a model given as is.
  AdaptiveCloth* adaptive() { return adaptive_.get(); }
  const AdaptiveCloth* adaptive() const { return adaptive_.get(); }
  const AdaptiveReport* adaptive_report() const {
    return adaptive_ ? &adaptive_->report() : nullptr;
  }
  double time() const { return simulation().time(); }
  // #V by 3 current positions and #F by 3 current triangles.
  Eigen::MatrixX3d positions() const;
  const Eigen::MatrixX3i& faces() const;
  // #F: the input face each triangle descends from (a 4-8 mesh's quad or triangle); for a model
  // given as is, the constructor's (by default each triangle its own: 0, 1, ..., #F − 1).
  Eigen::VectorXi source_faces() const;
  // #F: each triangle's 4-8 level; empty for a model given as is.
  Eigen::VectorXi face_levels() const;

 private:
  std::unique_ptr<Simulation> fixed_;        // a model given as is
  std::unique_ptr<AdaptiveCloth> adaptive_;  // a 4-8 mesh
  Eigen::MatrixX3i fixed_faces_;             // the fixed model's triangles
  Eigen::VectorXi fixed_sources_;            // and their input faces
};

}  // namespace sd::sim
