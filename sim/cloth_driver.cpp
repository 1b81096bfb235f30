#include "sim/cloth_driver.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace sd::sim {

ClothDriver::ClothDriver(ClothModel model, Eigen::VectorXd x0, std::vector<Pin> pins,
                         SimulationSettings settings, Eigen::VectorXi source_faces) {
  const auto triangles = static_cast<Eigen::Index>(model.triangles.size());
  fixed_faces_.resize(triangles, 3);
  for (Eigen::Index t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k)
      fixed_faces_(t, k) = model.triangles[static_cast<std::size_t>(t)].vertices[k];
  if (source_faces.size() == 0)
    source_faces = Eigen::VectorXi::LinSpaced(triangles, 0, static_cast<int>(triangles) - 1);
  if (source_faces.size() != triangles)
    throw std::invalid_argument("the input faces must be given for every triangle (" +
                                std::to_string(source_faces.size()) + " given, " +
                                std::to_string(triangles) + " triangles)");
  fixed_sources_ = std::move(source_faces);
  fixed_ = std::make_unique<Simulation>(std::move(model), std::move(x0), std::move(pins),
                                        std::move(settings));
}

ClothDriver::ClothDriver(meshing::Mesh48 mesh, AdaptiveMaterial material,
                         Eigen::MatrixX3d positions, std::vector<Pin> pins,
                         SimulationSettings settings, AdaptiveSettings adaptive)
    : adaptive_(std::make_unique<AdaptiveCloth>(std::move(mesh), std::move(material),
                                                std::move(positions), std::move(pins),
                                                std::move(settings), adaptive)) {}

ClothDriver::~ClothDriver() = default;
ClothDriver::ClothDriver(ClothDriver&&) noexcept = default;
ClothDriver& ClothDriver::operator=(ClothDriver&&) noexcept = default;

void ClothDriver::set_body(const meshing::TriMesh& body) {
  if (adaptive_)
    adaptive_->set_body(body);
  else
    fixed_->set_body(body);
}

void ClothDriver::set_body_motion(PoseSequence motion) {
  if (adaptive_)
    adaptive_->set_body_motion(std::move(motion));
  else
    fixed_->set_body_motion(std::move(motion));
}

void ClothDriver::set_velocities(const Eigen::VectorXd& v) {
  if (adaptive_)
    throw std::invalid_argument("start velocities are not supported for adaptive cloth");
  fixed_->set_velocities(v);
}

StepOutcome ClothDriver::step(double max_step) {
  return adaptive_ ? adaptive_->step(max_step) : fixed_->step(max_step);
}

SimulationReport ClothDriver::run(const ClothObserver& observer) {
  Simulation::RunHooks hooks;
  hooks.step = [&](double max_step) {
    if (observer.before_step) observer.before_step(*this);
    if (observer.max_step) max_step = std::min(max_step, observer.max_step(*this));
    return step(max_step);
  };
  if (observer.after_step)
    hooks.after_step = [&](const StepOutcome& outcome) {
      return observer.after_step(*this, outcome);
    };
  if (adaptive_) return adaptive_->run(hooks).simulation;
  return fixed_->run(hooks);
}

const Simulation& ClothDriver::simulation() const {
  return adaptive_ ? adaptive_->simulation() : *fixed_;
}

Eigen::MatrixX3d ClothDriver::positions() const {
  return adaptive_ ? adaptive_->positions() : unflatten_positions(fixed_->positions());
}

const Eigen::MatrixX3i& ClothDriver::faces() const {
  return adaptive_ ? adaptive_->faces() : fixed_faces_;
}

Eigen::VectorXi ClothDriver::source_faces() const {
  return adaptive_ ? adaptive_->source_faces() : fixed_sources_;
}

Eigen::VectorXi ClothDriver::face_levels() const {
  return adaptive_ ? adaptive_->face_levels() : Eigen::VectorXi();
}

}  // namespace sd::sim
