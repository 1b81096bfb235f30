#include "garment/panel_grain.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace sd::garment {
namespace {

// How far below the crotch (fraction of the body's height) a panel must reach to be on a leg,
// and where the top of the leg's axis is taken: 2 % is 3.5 cm on a 1.75 m figure, below the
// crotch's own slice (where the legs are not yet apart).
constexpr double kBelowCrotch = 0.02;
// A garment section nearer the median plane than this (m) reaches it: a skirt's centre seam
// lies on x = 0, a trouser leg's inseam at mid-thigh 3 cm or more from it.
constexpr double kMedianReach = 0.01;

std::optional<BodyPart> limb_of(const std::string& body_part) {
  for (const BodyPart part :
       {BodyPart::kLeftArm, BodyPart::kRightArm, BodyPart::kLeftLeg, BodyPart::kRightLeg})
    if (body_part_name(part) == body_part) return part;
  return std::nullopt;
}

const PanelSpec* spec_of(const GarmentRequest& sketch, const GarmentPanel& panel) {
  const std::string base = panel.mirror_copy
                               ? panel.id.substr(0, panel.id.size() - std::string(".mirror").size())
                               : panel.id;
  for (const PanelSpec& spec : sketch.panels)
    if (spec.id == base) return &spec;
  return nullptr;
}

// Whether the garment's section at height y comes within kMedianReach of x = 0.
bool section_reaches_median(const meshing::QuadMesh& mesh, double y) {
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, k)).transpose();
      const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, (k + 1) % 4)).transpose();
      if ((a.y() - y) * (b.y() - y) > 0 || a.y() == b.y()) continue;
      const double t = (y - a.y()) / (b.y() - a.y());
      if (std::abs(a.x() + t * (b.x() - a.x())) < kMedianReach) return true;
    }
  return false;
}

}  // namespace

std::vector<Eigen::Vector3d> limb_axis(const BodyLandmarks& landmarks, const meshing::TriMesh& body,
                                       BodyPart limb) {
  const auto at = [&](const std::string& name) { return landmarks.find(name)->position; };
  const bool left = limb == BodyPart::kLeftArm || limb == BodyPart::kLeftLeg;
  const std::string side = left ? "left_" : "right_";
  if (limb == BodyPart::kLeftArm || limb == BodyPart::kRightArm)
    return {at(side + "shoulder"), at(side + "elbow"), at(side + "wrist")};
  // The top of the leg: the centre of its outline a little below the crotch, else the knee
  // straight above (a body whose legs join lower than the landmark says).
  const Eigen::Vector3d knee = at(side + "knee");
  const double height = body.vertices.col(1).maxCoeff();
  const double y = at("crotch").y() - kBelowCrotch * height;
  Eigen::Vector3d top(knee.x(), y, knee.z());
  double best = std::numeric_limits<double>::infinity();
  for (const SliceOutline& o : slice_body(body, y))
    if (o.centroid.x() * (left ? 1 : -1) > 0 && std::abs(o.centroid.x() - knee.x()) < best)
      best = std::abs(o.centroid.x() - knee.x()), top = o.centroid;
  return {top, knee, at(side + "ankle")};
}

Eigen::Vector3d limb_direction(const std::vector<Eigen::Vector3d>& axis,
                               const Eigen::MatrixX3d& points, const Eigen::VectorXd& weights) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p = points.row(i).transpose();
    double nearest = std::numeric_limits<double>::infinity();
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();
    for (size_t s = 1; s < axis.size(); ++s) {
      const Eigen::Vector3d d = axis[s - 1] - axis[s];  // towards the torso
      if (d.squaredNorm() == 0) continue;
      const double t = std::clamp((p - axis[s]).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const double distance = (p - axis[s] - t * d).norm();
      if (distance < nearest) nearest = distance, direction = d.normalized();
    }
    sum += weights(i) * direction;
  }
  return sum.norm() > 0 ? Eigen::Vector3d(sum.normalized()) : Eigen::Vector3d::UnitY();
}

void choose_grain(const GarmentRequest& sketch, const meshing::TriMesh& body,
                  const BodyLandmarks* landmarks, Garment& garment) {
  const meshing::QuadMesh& mesh = garment.mesh;
  const double height = body.vertices.col(1).maxCoeff() - body.vertices.col(1).minCoeff();
  for (size_t p = 0; p < garment.panels.size(); ++p) {
    GarmentPanel& panel = garment.panels[p];
    const PanelSpec* spec = spec_of(sketch, panel);
    const GrainSpec grain = spec != nullptr ? spec->grain : GrainSpec{};
    panel.grain = "vertical";
    panel.grain_axis = Eigen::Vector3d::UnitY();
    panel.grain_turn_deg = panel.mirror_copy ? -grain.turn_deg : grain.turn_deg;
    if (grain.rule == GrainRule::kVertical) continue;
    const std::optional<BodyPart> limb = limb_of(panel.body_part);
    if (grain.rule == GrainRule::kLimb && (limb == std::nullopt || landmarks == nullptr))
      sketch.fail(
          (spec != nullptr ? spec->json_path : std::string("/panels")) + "/grain",
          landmarks == nullptr
              ? fmt::format("panel '{}' asks for its grain along a limb, but the body is not a "
                            "standing figure whose arms and legs can be found; use \"vertical\"",
                            panel.id)
              : fmt::format("panel '{}' asks for its grain along a limb, but it lies on the {} "
                            "(its faces' nearest body region), not on an arm or a leg; use "
                            "\"vertical\" or \"auto\"",
                            panel.id, panel.body_part));
    if (limb == std::nullopt || landmarks == nullptr) continue;
    // The panel's quad centres and areas.
    std::vector<Eigen::Index> quads;
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
      if (garment.face_panel(f) == static_cast<int>(p)) quads.push_back(f);
    Eigen::MatrixX3d centres(static_cast<Eigen::Index>(quads.size()), 3);
    Eigen::VectorXd areas(centres.rows());
    double lowest = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < quads.size(); ++i) {
      const Eigen::Index f = quads[i];
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        c += mesh.vertices.row(mesh.faces(f, k)).transpose();
        lowest = std::min(lowest, mesh.vertices(mesh.faces(f, k), 1));
      }
      centres.row(static_cast<Eigen::Index>(i)) = 0.25 * c.transpose();
      const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose(),
                            b = mesh.vertices.row(mesh.faces(f, 1)).transpose(),
                            cc = mesh.vertices.row(mesh.faces(f, 2)).transpose(),
                            d = mesh.vertices.row(mesh.faces(f, 3)).transpose();
      areas(static_cast<Eigen::Index>(i)) = 0.5 * (cc - a).cross(d - b).norm();
    }
    const bool leg = *limb == BodyPart::kLeftLeg || *limb == BodyPart::kRightLeg;
    if (leg && grain.rule == GrainRule::kAuto) {
      // Round one leg only: below the crotch, with the garment's section halfway down away
      // from the median plane (a skirt's centre seam lies on it).
      const double crotch = landmarks->find("crotch")->position.y();
      if (!(lowest < crotch - kBelowCrotch * height) ||
          section_reaches_median(mesh, 0.5 * (crotch + lowest)))
        continue;
    }
    panel.grain = "limb";
    panel.grain_axis = limb_direction(limb_axis(*landmarks, body, *limb), centres, areas);
  }
  // A mirror copy takes its original's axis reflected, so that the copy stays the reflection.
  for (GarmentPanel& copy : garment.panels) {
    if (!copy.mirror_copy) continue;
    const std::string base = copy.id.substr(0, copy.id.size() - std::string(".mirror").size());
    for (const GarmentPanel& original : garment.panels)
      if (original.id == base && !original.mirror_copy) {
        copy.grain = original.grain;
        copy.grain_axis = original.grain_axis;
        copy.grain_axis.x() *= -1.0;
      }
  }
}

}  // namespace sd::garment
