#include "sim/body_motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace sd::sim {

namespace {

// 0 below `edge0`, 1 above `edge1`, C¹ cubic in between.
double smoothstep(double edge0, double edge1, double x) {
  const double s = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return s * s * (3.0 - 2.0 * s);
}

}  // namespace

PoseSequence::PoseSequence(Eigen::MatrixX3i faces, std::vector<double> times,
                           std::vector<Eigen::MatrixX3d> poses)
    : faces_(std::move(faces)), times_(std::move(times)), poses_(std::move(poses)) {
  if (poses_.empty()) throw InvalidBodyMotionError("a body motion needs at least one pose");
  if (times_.size() != poses_.size())
    throw InvalidBodyMotionError("a body motion has " + std::to_string(poses_.size()) +
                                 " poses but " + std::to_string(times_.size()) + " times");
  for (std::size_t k = 0; k < times_.size(); ++k) {
    if (!std::isfinite(times_[k]))
      throw InvalidBodyMotionError("pose " + std::to_string(k) + " has a non-finite time");
    if (k > 0 && !(times_[k] > times_[k - 1]))
      throw InvalidBodyMotionError("pose times must increase strictly (pose " + std::to_string(k) +
                                   " is at " + std::to_string(times_[k]) + " s, not after " +
                                   std::to_string(times_[k - 1]) + " s)");
    if (poses_[k].rows() != poses_.front().rows())
      throw InvalidBodyMotionError("pose " + std::to_string(k) + " has " +
                                   std::to_string(poses_[k].rows()) +
                                   " vertices; every pose must have the same vertices as the "
                                   "first (" +
                                   std::to_string(poses_.front().rows()) + ")");
    if (!poses_[k].allFinite())
      throw InvalidBodyMotionError("pose " + std::to_string(k) + " has a non-finite coordinate");
  }
  if (faces_.size() > 0 && (faces_.minCoeff() < 0 || faces_.maxCoeff() >= vertex_count()))
    throw InvalidBodyMotionError(
        "a face of the moving body refers to a vertex that does not "
        "exist");
}

int PoseSequence::segment(double t) const {
  const auto after = std::upper_bound(times_.begin(), times_.end(), t);
  const int k = static_cast<int>(after - times_.begin()) - 1;
  return std::clamp(k, 0, std::max(0, keyframe_count() - 2));
}

Eigen::MatrixX3d PoseSequence::vertices_at(double t) const {
  if (keyframe_count() == 1 || t <= times_.front()) return poses_.front();
  if (t >= times_.back()) return poses_.back();
  const int k = segment(t);
  const double s = (t - times_[k]) / (times_[k + 1] - times_[k]);
  return (1.0 - s) * poses_[k] + s * poses_[k + 1];
}

meshing::TriMesh PoseSequence::mesh_at(double t) const {
  meshing::TriMesh mesh;
  mesh.vertices = vertices_at(t);
  mesh.faces = faces_;
  return mesh;
}

Eigen::MatrixX3d PoseSequence::velocity_at(double t) const {
  if (keyframe_count() == 1 || t < times_.front() || t >= times_.back())
    return Eigen::MatrixX3d::Zero(vertex_count(), 3);
  const int k = segment(t);
  return (poses_[k + 1] - poses_[k]) / (times_[k + 1] - times_[k]);
}

Eigen::MatrixX3d PoseSequence::average_velocity(double t0, double t1) const {
  if (!(t1 != t0)) return velocity_at(t0);
  return (vertices_at(t1) - vertices_at(t0)) / (t1 - t0);
}

void move_body(BodyCollider& collider, const PoseSequence& motion, double t0, double t1) {
  if (!(t1 > t0)) throw std::invalid_argument("a body step needs t1 > t0");
  const std::vector<double>& times = motion.times();
  const Eigen::MatrixX3d velocity = motion.average_velocity(t0, t1);
  if (motion.keyframe_count() == 1) {
    collider.set_pose_on_segment(motion.keyframe(0), motion.keyframe(0), 0.0, 0.0, velocity);
    return;
  }
  const double start = std::clamp(t0, times.front(), times.back());
  const double end = std::clamp(t1, times.front(), times.back());
  // The segment holding the step's start; a start on a keyframe belongs to the segment after it
  // unless it is the last keyframe.
  const int last = motion.keyframe_count() - 2;
  int k = static_cast<int>(std::upper_bound(times.begin(), times.end(), start) - times.begin()) - 1;
  k = std::clamp(k, 0, last);
  if (end <= times[k + 1]) {
    const double length = times[k + 1] - times[k];
    collider.set_pose_on_segment(motion.keyframe(k), motion.keyframe(k + 1),
                                 std::clamp((start - times[k]) / length, 0.0, 1.0),
                                 std::clamp((end - times[k]) / length, 0.0, 1.0), velocity);
  } else {
    collider.set_pose(motion.vertices_at(t1), velocity);
  }
}

PoseSequence make_pose_sequence(const meshing::TriMesh& rest, const std::vector<double>& times,
                                const std::function<Eigen::MatrixX3d(double)>& displacement) {
  std::vector<Eigen::MatrixX3d> poses;
  poses.reserve(times.size());
  for (const double t : times) {
    Eigen::MatrixX3d d = displacement(t);
    if (d.rows() != rest.vertex_count())
      throw InvalidBodyMotionError("a displacement field has " + std::to_string(d.rows()) +
                                   " rows for a body of " + std::to_string(rest.vertex_count()) +
                                   " vertices");
    poses.push_back(rest.vertices + d);
  }
  return PoseSequence(rest.faces, times, std::move(poses));
}

Eigen::VectorXd arm_rotation_weights(const meshing::TriMesh& rest,
                                     const ArmLoweringOptions& options) {
  const meshing::BoundingBox box = meshing::bounding_box(rest);
  const double height = box.extent().y();
  if (!(height > 0.0)) throw InvalidBodyMotionError("the body has no height to find its arms");
  const double tilt = options.arm_tilt_degrees * std::numbers::pi / 180.0;
  // In the frontal plane, for the figure's left side (x > 0; the right side is mirrored):
  const Eigen::Vector2d joint(options.shoulder_offset * height,
                              box.min.y() + options.shoulder_height * height);
  const Eigen::Vector2d along(std::sin(tilt), -std::cos(tilt));  // down the arm
  const Eigen::Vector2d across(std::cos(tilt), std::sin(tilt));  // away from the torso
  const double boundary = -options.arm_boundary * height;
  const double boundary_width = 0.007 * height;  // soft edge of the arm selection, ~1.2 cm
  const double blend = options.blend_length * height;

  Eigen::VectorXd weights(rest.vertex_count());
  for (Eigen::Index v = 0; v < rest.vertex_count(); ++v) {
    const Eigen::Vector2d q(std::abs(rest.vertices(v, 0)), rest.vertices(v, 1));
    const Eigen::Vector2d r = q - joint;
    const double on_arm =
        smoothstep(boundary - boundary_width, boundary + boundary_width, r.dot(across));
    const double below_joint = smoothstep(0.0, blend, r.dot(along));
    weights[v] = on_arm * below_joint;
  }
  // Diffuse the weights along the surface (Jacobi averaging over mesh neighbours): where arm and
  // torso skin meet in the armpit fold, the selection above jumps within a few centimetres.
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(rest.vertex_count()));
  for (Eigen::Index f = 0; f < rest.face_count(); ++f)
    for (int k = 0; k < 3; ++k)
      neighbours[rest.faces(f, k)].push_back(rest.faces(f, (k + 1) % 3)),
          neighbours[rest.faces(f, (k + 1) % 3)].push_back(rest.faces(f, k));
  for (int iteration = 0; iteration < options.smoothing_iterations; ++iteration) {
    Eigen::VectorXd next = weights;
    for (Eigen::Index v = 0; v < rest.vertex_count(); ++v) {
      if (neighbours[v].empty()) continue;
      double sum = 0.0;
      for (const int u : neighbours[v]) sum += weights[u];
      next[v] = 0.5 * weights[v] + 0.5 * sum / static_cast<double>(neighbours[v].size());
    }
    weights = next;
  }
  // Diffusion leaves a faint tail on the torso and takes a little off the hand: snap both ends
  // back with a C¹ ramp, so the torso stays exactly still and the forearm turns rigidly.
  if (options.smoothing_iterations > 0)
    for (Eigen::Index v = 0; v < rest.vertex_count(); ++v)
      weights[v] = smoothstep(0.1, 0.9, weights[v]);
  return weights;
}

PoseSequence make_arm_lowering(const meshing::TriMesh& rest, const ArmLoweringOptions& options) {
  if (options.keyframes < 2) throw InvalidBodyMotionError("arm lowering needs at least 2 poses");
  if (!(options.duration > 0.0))
    throw InvalidBodyMotionError("arm lowering needs a positive duration");
  if (!(options.start >= 0.0))
    throw InvalidBodyMotionError("arm lowering cannot start before the drape (negative start)");
  const Eigen::VectorXd weights = arm_rotation_weights(rest, options);
  const meshing::BoundingBox box = meshing::bounding_box(rest);
  const double height = box.extent().y();
  const Eigen::Vector2d joint(options.shoulder_offset * height,
                              box.min.y() + options.shoulder_height * height);
  const double full_angle = options.angle_degrees * std::numbers::pi / 180.0;

  std::vector<double> times;
  for (int k = 0; k < options.keyframes; ++k)
    times.push_back(options.start + options.duration * k / (options.keyframes - 1));
  return make_pose_sequence(rest, times, [&](double t) {
    const double angle =
        full_angle * smoothstep(options.start, options.start + options.duration, t);
    Eigen::MatrixX3d displacement = Eigen::MatrixX3d::Zero(rest.vertex_count(), 3);
    for (Eigen::Index v = 0; v < rest.vertex_count(); ++v) {
      if (weights[v] == 0.0) continue;
      const double side = rest.vertices(v, 0) >= 0.0 ? 1.0 : -1.0;
      const Eigen::Vector2d r(side * rest.vertices(v, 0) - joint.x(),
                              rest.vertices(v, 1) - joint.y());
      // Lowering turns the left arm clockwise seen from the front (towards −x); mirrored on the
      // right.
      const double phi = -weights[v] * angle;
      const Eigen::Vector2d turned(std::cos(phi) * r.x() - std::sin(phi) * r.y(),
                                   std::sin(phi) * r.x() + std::cos(phi) * r.y());
      displacement(v, 0) = side * (turned.x() - r.x());
      displacement(v, 1) = turned.y() - r.y();
    }
    return displacement;
  });
}

}  // namespace sd::sim
