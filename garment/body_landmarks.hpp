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
};

struct BodyLandmarks {
  std::vector<Landmark> points;  // neck_base, shoulders, armpits, chest, waist, hips, crotch,
                                 // elbows, wrists, knees, ankles (left before right)
  double chest_girth = 0.0;      // m, around the torso's convex hull (a tape measure's path)
  double waist_girth = 0.0;
  double hip_girth = 0.0;
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
