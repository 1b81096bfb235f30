#pragma once
// A moving body: a sequence of poses (vertex positions at given times) of one triangle mesh,
// interpolated linearly in time. The collider is refitted from the pose at each step.
// Builders: from any per-vertex displacement function of time, and the mannequin's arms lowering
// from the A-pose (rotation about each shoulder, blended smoothly near the armpit).

#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "sim/body_collider.hpp"

namespace sd::sim {

// A pose sequence that cannot be used (no poses, times not increasing, a pose whose vertex count
// differs from the mesh). Derives from std::invalid_argument: the input is wrong.
class InvalidBodyMotionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class PoseSequence {
 public:
  // `poses[k]` (#V by 3, metres) is the body at `times[k]` (seconds, strictly increasing); all
  // share `faces`. Throws InvalidBodyMotionError.
  PoseSequence(Eigen::MatrixX3i faces, std::vector<double> times,
               std::vector<Eigen::MatrixX3d> poses);

  int keyframe_count() const { return static_cast<int>(times_.size()); }
  int vertex_count() const { return static_cast<int>(poses_.front().rows()); }
  double start_time() const { return times_.front(); }
  double end_time() const { return times_.back(); }
  const std::vector<double>& times() const { return times_; }
  const Eigen::MatrixX3i& faces() const { return faces_; }
  const Eigen::MatrixX3d& keyframe(int k) const { return poses_[k]; }

  // Positions at time t, #V by 3: linear between keyframes, held before the first and after the
  // last.
  Eigen::MatrixX3d vertices_at(double t) const;
  meshing::TriMesh mesh_at(double t) const;
  // Velocity at time t, #V by 3 (m/s): the slope of the segment containing t (the later one at a
  // keyframe), zero outside [start, end].
  Eigen::MatrixX3d velocity_at(double t) const;
  // Mean velocity over [t0, t1], #V by 3: (x(t1) − x(t0)) / (t1 − t0). What a cloth step from t0
  // to t1 sees of the body's motion.
  Eigen::MatrixX3d average_velocity(double t0, double t1) const;

 private:
  int segment(double t) const;  // k with times[k] <= t < times[k+1], clamped to a valid segment

  Eigen::MatrixX3i faces_;
  std::vector<double> times_;
  std::vector<Eigen::MatrixX3d> poses_;
};

// Moves `collider` (built on this sequence's mesh) for a cloth step from t0 to t1 > t0, with the
// step's mean body velocity. Within one keyframe segment the body moves on a straight line and
// the collider is refitted only when the segment changes (set_pose_on_segment); a step that
// spans a keyframe falls back to set_pose on the pose at t1 (its chord).
void move_body(BodyCollider& collider, const PoseSequence& motion, double t0, double t1);

// Keyframes at `times` with positions rest + displacement(t) (#V by 3 each).
PoseSequence make_pose_sequence(const meshing::TriMesh& rest, const std::vector<double>& times,
                                const std::function<Eigen::MatrixX3d(double)>& displacement);

// The arms of an A-pose mannequin (metres, +Y up, facing +Z, feet at y = 0, centred on x = 0)
// rotating towards the body in the frontal plane about each shoulder joint. Geometry defaults
// are fractions of the body height measured on the built-in mannequin.
struct ArmLoweringOptions {
  double angle_degrees = 10.0;  // rotation at the end; negative raises the arms
  double start = 0.0;           // seconds: the arms start moving then (held before)
  double duration = 1.0;        // seconds from start to end
  int keyframes = 6;  // poses over the duration (≥ 2): rotations are sampled, not lerped
  double shoulder_height = 0.80;   // joint centre height / body height
  double shoulder_offset = 0.109;  // joint centre |x| / body height
  double arm_tilt_degrees = 17.0;  // angle of the rest arm axis from the vertical
  // A vertex belongs to the arm when it lies outside the line through the joint at the arm's
  // tilt, offset inwards by this fraction of the height (the gap between arm and torso).
  double arm_boundary = 0.040;
  double blend_length =
      0.06;  // fraction of height over which the rotation fades in below the joint
  int smoothing_iterations = 30;  // averaging passes over mesh neighbours (softens the armpit)
};

// Per-vertex share of the arm rotation in [0, 1] (0 on the torso and head, 1 on the forearm).
Eigen::VectorXd arm_rotation_weights(const meshing::TriMesh& rest,
                                     const ArmLoweringOptions& options = {});

// Keyframes of the arms lowering from the rest (A-)pose, evenly spaced over the duration, with an
// ease-in-out angle profile so the motion starts and stops smoothly.
PoseSequence make_arm_lowering(const meshing::TriMesh& rest,
                               const ArmLoweringOptions& options = {});

}  // namespace sd::sim
