#include "sim/body_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "garment/body.hpp"
#include "meshing/tri_mesh.hpp"
#include "sim/body_collider.hpp"

namespace sd::sim {
namespace {

meshing::TriMesh tetrahedron() {
  meshing::TriMesh mesh;
  mesh.vertices.resize(4, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  mesh.faces.resize(4, 3);
  mesh.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return mesh;
}

TEST(PoseSequence, ExactAtKeyframesAndLinearBetween) {
  const meshing::TriMesh rest = tetrahedron();
  const Eigen::MatrixX3d p0 = rest.vertices;
  const Eigen::MatrixX3d p1 = rest.vertices.array() + 0.5;
  const Eigen::MatrixX3d p2 = 2.0 * rest.vertices;
  const PoseSequence sequence(rest.faces, {0.0, 0.5, 2.0}, {p0, p1, p2});
  EXPECT_EQ(sequence.keyframe_count(), 3);
  EXPECT_EQ(sequence.vertices_at(0.0), p0);
  EXPECT_EQ(sequence.vertices_at(0.5), p1);
  EXPECT_EQ(sequence.vertices_at(2.0), p2);
  EXPECT_LT((sequence.vertices_at(0.25) - 0.5 * (p0 + p1)).norm(), 1e-15);
  EXPECT_LT((sequence.vertices_at(1.625) - (0.25 * p1 + 0.75 * p2)).norm(), 1e-15);
  EXPECT_EQ(sequence.vertices_at(-1.0), p0);  // held before the start
  EXPECT_EQ(sequence.vertices_at(7.0), p2);   // and after the end
  EXPECT_EQ(sequence.mesh_at(1.0).faces, rest.faces);

  EXPECT_LT((sequence.velocity_at(0.1) - (p1 - p0) / 0.5).norm(), 1e-12);
  EXPECT_LT((sequence.velocity_at(0.5) - (p2 - p1) / 1.5).norm(), 1e-12);  // the later segment
  EXPECT_EQ(sequence.velocity_at(2.0), Eigen::MatrixX3d::Zero(4, 3));
  EXPECT_EQ(sequence.velocity_at(-0.1), Eigen::MatrixX3d::Zero(4, 3));
  // The mean velocity across a keyframe is the displacement over the interval.
  EXPECT_LT((sequence.average_velocity(0.25, 1.0) -
             (sequence.vertices_at(1.0) - sequence.vertices_at(0.25)) / 0.75)
                .norm(),
            1e-12);
}

TEST(PoseSequence, RejectsInconsistentPoses) {
  const meshing::TriMesh rest = tetrahedron();
  EXPECT_THROW(PoseSequence(rest.faces, {}, {}), InvalidBodyMotionError);
  EXPECT_THROW(PoseSequence(rest.faces, {0.0, 0.0}, {rest.vertices, rest.vertices}),
               InvalidBodyMotionError);
  EXPECT_THROW(PoseSequence(rest.faces, {0.0, 1.0}, {rest.vertices, Eigen::MatrixX3d::Zero(3, 3)}),
               InvalidBodyMotionError);
  EXPECT_THROW(PoseSequence(rest.faces, {0.0}, {rest.vertices, rest.vertices}),
               InvalidBodyMotionError);
}

TEST(PoseSequence, BuiltFromADisplacementField) {
  const meshing::TriMesh rest = tetrahedron();
  const PoseSequence sequence = make_pose_sequence(rest, {0.0, 1.0, 2.0}, [&](double t) {
    Eigen::MatrixX3d d = Eigen::MatrixX3d::Zero(4, 3);
    d.col(1).setConstant(t * t);  // rises along a parabola, sampled at the keyframes
    return d;
  });
  EXPECT_DOUBLE_EQ(sequence.vertices_at(2.0)(3, 1), 4.0);
  EXPECT_DOUBLE_EQ(sequence.vertices_at(1.5)(0, 1), 2.5);  // linear between keyframes
  EXPECT_DOUBLE_EQ(sequence.velocity_at(1.5)(2, 1), 3.0);
}

TEST(ArmLowering, KeepsTopologyAndLowersTheHands) {
  const garment::Body body = garment::load_body("builtin");
  const meshing::TriMesh& rest = body.mesh;
  ArmLoweringOptions options;
  options.angle_degrees = 10.0;
  const PoseSequence sequence = make_arm_lowering(rest, options);
  EXPECT_EQ(sequence.faces(), rest.faces);
  EXPECT_EQ(sequence.vertex_count(), rest.vertex_count());
  EXPECT_EQ(sequence.vertices_at(0.0), rest.vertices);

  const Eigen::VectorXd weights = arm_rotation_weights(rest, options);
  // Head, torso and legs stay; the hands turn fully.
  Eigen::Index left_tip = 0, right_tip = 0;
  for (Eigen::Index v = 0; v < rest.vertex_count(); ++v) {
    if (rest.vertices(v, 0) > rest.vertices(left_tip, 0)) left_tip = v;
    if (rest.vertices(v, 0) < rest.vertices(right_tip, 0)) right_tip = v;
    const double x = std::abs(rest.vertices(v, 0)), y = rest.vertices(v, 1);
    if (x < 0.1 || (y < 0.9 && x < 0.2) || y > 1.5) {
      EXPECT_EQ(weights[v], 0.0) << v;
    }
  }
  EXPECT_EQ(weights[left_tip], 1.0);
  EXPECT_EQ(weights[right_tip], 1.0);

  const Eigen::MatrixX3d end = sequence.vertices_at(options.duration);
  const double height = meshing::bounding_box(rest).extent().y();
  const Eigen::Vector2d joint(options.shoulder_offset * height, options.shoulder_height * height);
  const double angle = options.angle_degrees * M_PI / 180.0;
  for (const Eigen::Index tip : {left_tip, right_tip}) {
    const double side = rest.vertices(tip, 0) > 0 ? 1.0 : -1.0;
    const Eigen::Vector2d r(side * rest.vertices(tip, 0) - joint.x(),
                            rest.vertices(tip, 1) - joint.y());
    // A rigid turn of the hand about the joint, towards the body.
    const Eigen::Vector2d turned(std::cos(angle) * r.x() + std::sin(angle) * r.y(),
                                 -std::sin(angle) * r.x() + std::cos(angle) * r.y());
    EXPECT_NEAR(end(tip, 0), side * (joint.x() + turned.x()), 1e-12);
    EXPECT_NEAR(end(tip, 1), joint.y() + turned.y(), 1e-12);
    EXPECT_EQ(end(tip, 2), rest.vertices(tip, 2));
    // ~0.6 m from the joint at ~17°: 10° more brings the tip ~7 cm in and ~2.5 cm down.
    EXPECT_GT(end(tip, 1) - rest.vertices(tip, 1), -0.04);
    EXPECT_LT(end(tip, 1) - rest.vertices(tip, 1), -0.015);
    EXPECT_LT(side * (end(tip, 0) - rest.vertices(tip, 0)), -0.05);
  }
  // The figure stays mirror-symmetric.
  EXPECT_NEAR(end(left_tip, 0), -end(right_tip, 0), 1e-9);

  // No tearing: no edge stretches by more than 10% (the smoothed blend spreads the turn); the
  // armpit fold closes as the arm comes in, so edges across it may shorten, but none collapses.
  double stretch = 1.0, shrink = 1.0;
  for (Eigen::Index f = 0; f < rest.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = rest.faces(f, k), b = rest.faces(f, (k + 1) % 3);
      const double ratio =
          (end.row(a) - end.row(b)).norm() / (rest.vertices.row(a) - rest.vertices.row(b)).norm();
      stretch = std::max(stretch, ratio);
      shrink = std::min(shrink, ratio);
    }
  EXPECT_LT(stretch, 1.1);
  EXPECT_GT(shrink, 0.5);

  // Mid-motion the body moves; at the ends it rests.
  EXPECT_GT(sequence.velocity_at(0.5 * options.duration).rowwise().norm().maxCoeff(), 0.05);
  EXPECT_EQ(sequence.velocity_at(options.duration), Eigen::MatrixX3d::Zero(rest.vertex_count(), 3));

  // The collider follows the sequence: after refitting to the end pose, the hand tip is on the
  // surface and a point where the hand was at rest is now clear of it.
  BodyCollider collider(rest);
  collider.set_pose(end, sequence.average_velocity(0.9 * options.duration, options.duration));
  EXPECT_NEAR(collider.signed_distance(end.row(left_tip).transpose()), 0.0, 1e-12);
  EXPECT_GT(collider.signed_distance(rest.vertices.row(left_tip).transpose()), 0.01);
}

TEST(ArmLowering, StartsLaterWithTheSameMotion) {
  // Started at 1 s (a garment settles first), the motion is the one started at 0 shifted by 1 s,
  // and the body holds its rest pose until then.
  const garment::Body body = garment::load_body("builtin");
  ArmLoweringOptions options;
  const PoseSequence now = make_arm_lowering(body.mesh, options);
  options.start = 1.0;
  const PoseSequence later = make_arm_lowering(body.mesh, options);
  EXPECT_DOUBLE_EQ(later.start_time(), 1.0);
  EXPECT_DOUBLE_EQ(later.end_time(), 2.0);
  EXPECT_EQ(later.vertices_at(0.5), body.mesh.vertices);
  for (const double t : {0.1, 0.37, 0.5, 0.9})
    EXPECT_LT((later.vertices_at(1.0 + t) - now.vertices_at(t)).cwiseAbs().maxCoeff(), 1e-12) << t;
  options.start = -1.0;
  EXPECT_THROW(make_arm_lowering(body.mesh, options), InvalidBodyMotionError);
}

TEST(MoveBody, FollowsTheSequenceWithOneRefitPerSegment) {
  const garment::Body body = garment::load_body("builtin");
  ArmLoweringOptions options;
  options.keyframes = 5;  // keyframes every 0.25 s
  const PoseSequence motion = make_arm_lowering(body.mesh, options);
  BodyCollider collider(body.mesh);
  const double dt = 1.0 / 16.0;
  for (int step = 0; step < 16; ++step) {
    move_body(collider, motion, step * dt, (step + 1) * dt);
    EXPECT_LT((collider.vertices() - motion.vertices_at((step + 1) * dt)).norm(), 1e-12) << step;
    EXPECT_LT((collider.previous_vertices() - motion.vertices_at(step * dt)).norm(), 1e-12);
  }
  EXPECT_EQ(collider.refit_count(), 4);
  // A step across a keyframe moves along the chord; after the end the body rests.
  move_body(collider, motion, 0.2, 0.3);
  EXPECT_LT((collider.vertices() - motion.vertices_at(0.3)).norm(), 1e-12);
  move_body(collider, motion, 1.0, 1.1);
  EXPECT_LT((collider.vertices() - motion.vertices_at(1.0)).norm(), 1e-12);
  EXPECT_EQ(collider.last_motion(), 0.0);
  EXPECT_THROW(move_body(collider, motion, 0.5, 0.5), std::invalid_argument);
}

TEST(MoveBody, ClothRidingOnTheMovingArmsIsNeverTakenForACrossing) {
  // Points 1 cm off the skin that move with the body (offset along the posed normals) while the
  // arms come down: the swept check must not call any of them a crossing, and no rigidly carried
  // point may end deeper than the armpit fold squeezes it.
  const garment::Body body = garment::load_body("builtin");
  ArmLoweringOptions options;
  options.duration = 0.5;
  const PoseSequence motion = make_arm_lowering(body.mesh, options);
  const auto riding = [&](double t) {
    const meshing::TriMesh pose = motion.mesh_at(t);
    const Eigen::MatrixX3d normals = meshing::vertex_normals(pose);
    Eigen::VectorXd x(3 * pose.vertex_count());
    for (Eigen::Index v = 0; v < pose.vertex_count(); ++v)
      x.segment<3>(3 * v) = (pose.vertices.row(v) + 0.01 * normals.row(v)).transpose();
    return x;
  };
  BodyCollider collider(body.mesh);
  ContactCache cache;
  ContactQuery query;
  int crossings = 0, samples = 0;
  const int steps = 12;
  Eigen::VectorXd x0 = riding(0.0);
  for (int step = 0; step < steps; ++step) {
    const double t0 = options.duration * step / steps, t1 = options.duration * (step + 1) / steps;
    move_body(collider, motion, t0, t1);
    const Eigen::VectorXd x1 = riding(t1);
    ContactQueryStats stats;
    for (const BodyContact& c : collider.find_contacts_swept(x0, x1, query, &cache, &stats)) {
      crossings += c.crossed ? 1 : 0;
      EXPECT_GT(c.distance, -0.015);
    }
    samples += stats.sweep_samples;
    x0 = x1;
  }
  EXPECT_EQ(crossings, 0);
  EXPECT_GT(samples, 0);  // the motion did make the check walk some paths
}

}  // namespace
}  // namespace sd::sim
