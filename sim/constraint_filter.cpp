#include "sim/constraint_filter.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sd::sim {

ConstraintFilter::ConstraintFilter(int vertex_count)
    : kind_(vertex_count, 0),
      first_(vertex_count, Eigen::Vector3d::Zero()),
      second_(vertex_count, Eigen::Vector3d::Zero()),
      target_(Eigen::VectorXd::Zero(3 * vertex_count)) {}

void ConstraintFilter::clear() {
  std::fill(kind_.begin(), kind_.end(), 0);
  target_.setZero();
  constrained_ = 0;
}

void ConstraintFilter::pin(int vertex, const Eigen::Vector3d& velocity) {
  if (kind_[vertex] == 0) ++constrained_;
  kind_[vertex] = 3;
  target_.segment<3>(3 * vertex) = velocity;
}

void ConstraintFilter::constrain_direction(int vertex, const Eigen::Vector3d& normal,
                                           double normal_velocity) {
  const double length = normal.norm();
  if (!(length > 0.0)) throw std::invalid_argument("a constraint direction must be non-zero");
  Eigen::Vector3d n = normal / length;
  unsigned char& kind = kind_[vertex];
  if (kind == 3) return;
  if (kind == 0) ++constrained_;
  auto target = target_.segment<3>(3 * vertex);
  if (kind == 1) {
    n -= n.dot(first_[vertex]) * first_[vertex];
    if (n.norm() < 1e-6) {  // same direction again: overwrite its value
      target = normal_velocity * first_[vertex];
      return;
    }
    n.normalize();
    second_[vertex] = n;
    target += normal_velocity * n;  // orthogonal to the first direction
    kind = 2;
    return;
  }
  if (kind == 2) {
    kind = 3;
    target += normal_velocity * first_[vertex].cross(second_[vertex]);
    return;
  }
  first_[vertex] = n;
  target = normal_velocity * n;
  kind = 1;
}

Eigen::Matrix3d ConstraintFilter::filter_matrix(int vertex) const {
  switch (kind_[vertex]) {
    case 0:
      return Eigen::Matrix3d::Identity();
    case 1:
      return Eigen::Matrix3d::Identity() - first_[vertex] * first_[vertex].transpose();
    case 2: {
      const Eigen::Vector3d t = first_[vertex].cross(second_[vertex]);
      return t * t.transpose();
    }
    default:
      return Eigen::Matrix3d::Zero();
  }
}

void ConstraintFilter::apply(Eigen::VectorXd& r) const {
  if (constrained_ == 0) return;
  for (int i = 0; i < vertex_count(); ++i) {
    auto ri = r.segment<3>(3 * i);
    switch (kind_[i]) {
      case 0:
        break;
      case 1:
        ri -= first_[i].dot(ri) * first_[i];
        break;
      case 2: {
        const Eigen::Vector3d t = first_[i].cross(second_[i]);
        ri = t.dot(ri) * t;
        break;
      }
      default:
        ri.setZero();
    }
  }
}

void ConstraintFilter::constrained_correction(const Eigen::VectorXd& v, Eigen::VectorXd& z) const {
  z.setZero(v.size());
  if (constrained_ == 0) return;
  for (int i = 0; i < vertex_count(); ++i) {
    if (kind_[i] == 0) continue;
    const Eigen::Vector3d vi = v.segment<3>(3 * i);
    const Eigen::Vector3d free_part = filter_matrix(i) * vi;
    // (I − S)(target − v) where the target already lies in the constrained subspace.
    z.segment<3>(3 * i) = target_.segment<3>(3 * i) - (vi - free_part);
  }
}

}  // namespace sd::sim
