#pragma once
// Which way the warp runs on each panel of a meshed garment (GrainSpec, garment_request.hpp):
// along the body's vertical, or along the axis of the limb the panel wraps. A sleeve drawn on an
// A-pose arm that takes the vertical's projection as its warp is cut up to the arm's angle off
// the arm (35° on a new user's top); along the limb's axis, which lies in every tangent plane of
// a tube round it, the warp runs down the sleeve on every side of it.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "garment/body_landmarks.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"

namespace sd::garment {

// A limb's axis as a polyline from where it leaves the torso to its far end (shoulder, elbow,
// wrist; top of the leg below the crotch, knee, ankle), m, in the normalised frame.
std::vector<Eigen::Vector3d> limb_axis(const BodyLandmarks& landmarks, const meshing::TriMesh& body,
                                       BodyPart limb);

// The unit direction along `axis` (pointing towards the torso) seen by the points `points`
// (#P by 3), each weighted (#P) by the segment nearest to it.
Eigen::Vector3d limb_direction(const std::vector<Eigen::Vector3d>& axis,
                               const Eigen::MatrixX3d& points, const Eigen::VectorXd& weights);

// Sets grain, grain_axis and grain_turn_deg of every panel of `garment`. "auto" takes the limb
// for a panel on an arm, and for a panel on a leg that goes round one leg only: the garment's
// section halfway between the crotch and the panel's lowest point does not reach the body's
// median plane (trousers, culottes), where a skirt's does. `landmarks` null (not a standing
// figure): every panel is vertical, and "limb" is refused. Throws SketchError (sketch.fail) for
// "limb" on a panel that is on no limb.
void choose_grain(const GarmentRequest& sketch, const meshing::TriMesh& body,
                  const BodyLandmarks* landmarks, Garment& garment);

}  // namespace sd::garment
