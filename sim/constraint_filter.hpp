#pragma once
// Per-vertex velocity constraints in the form the modified PCG needs (Baraff & Witkin 1998,
// §5.3): a filter S_i that removes the constrained directions of vertex i, and the value the
// solution must take in those directions. A pin constrains all three directions (S_i = 0);
// a contact will constrain its normal n (S_i = I − n nᵀ), two contacts two normals.

#include <Eigen/Core>
#include <vector>

namespace sd::sim {

class ConstraintFilter {
 public:
  ConstraintFilter() = default;
  explicit ConstraintFilter(int vertex_count);

  int vertex_count() const { return static_cast<int>(kind_.size()); }
  void clear();

  // All three directions fixed: the vertex's velocity will be `velocity`.
  void pin(int vertex, const Eigen::Vector3d& velocity);
  // The velocity component along unit `normal` will be `normal_velocity` (a contact). A second
  // call on the same vertex adds a second direction (made orthogonal to the first); a third
  // pins the vertex.
  void constrain_direction(int vertex, const Eigen::Vector3d& normal, double normal_velocity);

  bool is_free(int vertex) const { return kind_[vertex] == 0; }
  bool is_pinned(int vertex) const { return kind_[vertex] == 3; }
  // Number of constrained directions of a vertex (0..3; 3: pinned).
  int direction_count(int vertex) const { return kind_[vertex]; }
  // The first constrained unit direction (meaningful when direction_count ≥ 1).
  const Eigen::Vector3d& first_direction(int vertex) const { return first_[vertex]; }
  int constrained_count() const { return constrained_; }

  // S_i as a 3x3 matrix.
  Eigen::Matrix3d filter_matrix(int vertex) const;
  // r ← S r for a 3n vector.
  void apply(Eigen::VectorXd& r) const;
  // (I − S_i)·v_target: the constrained part of the prescribed velocity, 3n.
  const Eigen::VectorXd& constrained_velocity() const { return target_; }
  // z = (I − S)(v_target − v): the correction a solve from velocity v must make in the
  // constrained directions, 3n.
  void constrained_correction(const Eigen::VectorXd& v, Eigen::VectorXd& z) const;

 private:
  std::vector<unsigned char> kind_;      // number of constrained directions per vertex (0..3)
  std::vector<Eigen::Vector3d> first_;   // first constrained unit direction
  std::vector<Eigen::Vector3d> second_;  // second one (orthogonal to the first)
  Eigen::VectorXd target_;
  int constrained_ = 0;
};

}  // namespace sd::sim
