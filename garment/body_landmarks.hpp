#pragma once
// Landmarks of a standing, normalised body (metres, +Y up, facing +Z, feet on y = 0, its left
// at +x), found from horizontal slices of its mesh: where the legs join (crotch), where the
// arms leave the torso (armpits), the narrowest and widest girths of the torso (waist, hips,
// chest), the neck, and joints along the arm and leg axes placed by body proportions.
// docs/bodies.md ("Landmarks") says how each is found and how well.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "meshing/tri_mesh.hpp"

namespace sd::garment {

struct Landmark {
  std::string name;          // "left_armpit", "waist", ...
  Eigen::Vector3d position;  // m, normalised frame
  // m: the size of the body there, by which an offset from the landmark scales onto another
  // body: across (x), up (y) and front to back (z). At a torso landmark the torso's width, the
  // body's height and the torso's depth at the landmark's level (the chest's level for the
  // shoulders and armpits, the hips' for the crotch); at a limb's the limb's girth across and
  // front to back and the body's height up.
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
};

struct BodyLandmarks {
  std::vector<Landmark> points;  // neck_base, shoulders, armpits, chest, waist, hips, crotch,
                                 // elbows, wrists, knees, ankles (left before right)
  double chest_girth = 0.0;      // m, around the torso's convex hull (a tape measure's path)
  double waist_girth = 0.0;
  double hip_girth = 0.0;
  double height = 0.0;  // m, the body's top above the feet
  // Sentences saying which landmarks break a human figure's proportions (a low-polygon figure
  // whose torso is a box, shoulders found at the top of the head): found, but not to be
  // trusted. Empty for the built-in body and the Collada human.
  std::vector<std::string> doubts;

  // nullptr when there is no landmark of that name.
  const Landmark* find(std::string_view name) const;
  // The landmark that names p's place: the closest, but an elbow or a wrist only for a place near
  // the arm and the torso's levels (neck base, chest, waist, hips, crotch) mostly by height
  // (docs/bodies.md, "Landmarks"). The body has at least one.
  const Landmark& nearest(const Eigen::Vector3d& p) const;
};

// How far from x = 0 a landmark point may be written and still mean the mirror plane (m): `info`
// prints landmarks in millimetres and a designer types the offset so, each rounded by up to half
// a millimetre (the built-in left armpit at 0.176 and an offset of -0.176 across).
inline constexpr double kOnPlaneRounding = 0.001;

// The point `offset` (m) from landmark `l` of a body, written for another body whose landmarks are
// `drawn` (docs/sketch-format.md, "Points relative to a landmark"): across and front to back the
// offset scales by the two bodies' sizes at the landmark (Landmark::size); up, at a landmark of
// the torso or a leg, the height it reaches maps piecewise linearly between the two bodies'
// levels (feet, ankle, knee, crotch, hips, waist, chest, armpit, shoulder, neck base, top), so a
// hem written 39 cm below the hips, between knee and crotch, stays at that place between them;
// at an elbow or a wrist the offset scales by the bodies' heights. A point within
// kOnPlaneRounding of the drawn body's mirror plane x = 0 lands on this body's plane.
Eigen::Vector3d landmark_point_for(const BodyLandmarks& body, const BodyLandmarks& drawn,
                                   const Landmark& l, const Eigen::Vector3d& offset);

// One closed outline of a horizontal slice of the body (a leg, an arm, the torso).
struct SliceOutline {
  Eigen::Vector3d centroid;  // mean of the cut points, m
  Eigen::Vector3d min, max;  // bounding box of the cut points (y = the slice's height)
  double girth = 0.0;        // m, perimeter of the outline's convex hull (XZ)
};

// The outlines of the body's slice at height y, ordered by x of their centroids.
std::vector<SliceOutline> slice_body(const meshing::TriMesh& body, double y);

// The names find_landmarks gives, in order.
const std::vector<std::string>& landmark_names();

// Throws std::runtime_error when the mesh does not look like a standing figure with arms apart
// from the torso and two legs (no crotch or no armpit found), naming what is missing.
BodyLandmarks find_landmarks(const meshing::TriMesh& body);

}  // namespace sd::garment
