#include "garment/panel_grain.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/material_frames.hpp"
#include "garment/panel_flattening.hpp"
#include "garment/sketch_inputs.hpp"
#include "scene/sketch_file.hpp"

namespace sd::garment {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

scene::Sketch design(const std::string& name) {
  return scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs" / name);
}

const GarmentPanel& panel_named(const Garment& g, const std::string& id) {
  for (const GarmentPanel& p : g.panels)
    if (p.id == id) return p;
  throw std::runtime_error("no panel " + id);
}

// Degrees between a flattened piece's grain (+y) and the chord from the middle of the piece's
// edge along curve `from` to the middle of its edge along curve `to`: the sleeve's length runs
// from the cuff to the armhole, and a sleeve cut on grain has its grain along that.
double chord_off_grain(const Garment& g, const FlatPanel& piece, const std::string& from,
                       const std::string& to) {
  const auto middle = [&](const std::string& curve) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int count = 0;
    for (size_t l = 0; l < piece.vertices.size(); ++l)
      for (const auto& [edge, id] : g.edge_curve)
        if (id == curve && (edge.first == piece.vertices[l] || edge.second == piece.vertices[l])) {
          sum += piece.uv.row(static_cast<Eigen::Index>(l)).transpose();
          ++count;
          break;
        }
    EXPECT_GT(count, 1) << curve;
    return Eigen::Vector2d(sum / std::max(count, 1));
  };
  const Eigen::Vector2d chord = middle(to) - middle(from);
  return std::abs(std::atan2(chord.x(), chord.y())) / kDegree;
}

// The long-sleeved tee on the built-in body (its arms hang 13° to 21° off the vertical): with
// the vertical's projection as the warp, the sleeve pieces come out turned off their length;
// along the arm (the default for a panel on an arm) each sleeve's cuff-to-armhole line runs
// along the grain. The body panels keep the vertical.
TEST(PanelGrain, SleevesAreCutAlongTheArm) {
  scene::Sketch sketch = design("long-sleeve-tee.json");
  const Body body = load_sketch_body(sketch);
  const BodySurface surface(body.mesh);
  const Garment along = build_garment(sketch, surface);
  EXPECT_EQ(panel_named(along, "front").grain, "vertical");
  EXPECT_EQ(panel_named(along, "back").grain, "vertical");
  const FlatPattern flat = flatten_garment(along);
  for (const std::string sleeve : {"sleeve_front", "sleeve_back"}) {
    const GarmentPanel& panel = panel_named(along, sleeve);
    EXPECT_EQ(panel.grain, "limb");
    // Towards the shoulder and the torso (−x on the left arm), as the landmarks' axis runs.
    EXPECT_GT(panel.grain_axis.y(), 0.9);
    EXPECT_LT(panel.grain_axis.x(), -0.2);
    const std::string cuff = sleeve == "sleeve_front" ? "cuff_f" : "cuff_b";
    const std::string armhole = sleeve == "sleeve_front" ? "armhole_f" : "armhole_b";
    for (const FlatPanel& piece : flat.panels) {
      if (piece.id == sleeve) {
        EXPECT_LT(chord_off_grain(along, piece, cuff, armhole), 5.0);
      }
    }
  }
  // The same sleeves on the vertical grain: turned by the arm's angle.
  for (garment::PanelSpec& spec : sketch.panels) spec.grain.rule = GrainRule::kVertical;
  const Garment vertical = build_garment(sketch, surface);
  const FlatPattern upright = flatten_garment(vertical);
  for (const FlatPanel& piece : upright.panels) {
    if (piece.id == "sleeve_front") {
      EXPECT_GT(chord_off_grain(vertical, piece, "cuff_f", "armhole_f"), 10.0);
    }
  }
}

// A panel on a leg takes the leg's axis only when it goes round one leg: the culottes' legs do,
// the skirts' panels keep the vertical (their garment's centre seams hang on the median plane;
// the gored skirt's side gore too, which does not reach it itself).
TEST(PanelGrain, TrouserLegsFollowTheLegAndSkirtsHangOnTheVertical) {
  for (const auto& [file, id, grain] :
       {std::tuple{"culottes.json", "front", "limb"}, std::tuple{"culottes.json", "back", "limb"},
        std::tuple{"pencil-skirt.json", "skirt_front", "vertical"},
        std::tuple{"pencil-skirt.json", "skirt_back", "vertical"},
        std::tuple{"gored-skirt.json", "gore_front", "vertical"},
        std::tuple{"gored-skirt.json", "gore_side", "vertical"}}) {
    const scene::Sketch sketch = design(file);
    const Body body = load_sketch_body(sketch);
    const Garment g = build_garment(sketch, BodySurface(body.mesh));
    const GarmentPanel& panel = panel_named(g, id);
    EXPECT_EQ(panel.grain, grain) << file << " " << id;
    if (panel.grain == "limb") {
      // The built-in body's thigh leans in by a few degrees: near the vertical, not on it.
      const double lean = std::acos(panel.grain_axis.y()) / kDegree;
      EXPECT_GT(lean, 1.0) << id;
      EXPECT_LT(lean, 10.0) << id;
    }
  }
}

// A turn of 45° (a bias cut) sets every quad's warp 45° counter-clockwise, seen from outside,
// from the direction the rule gives, and the mirror copy's 45° the other way (its reflection).
TEST(PanelGrain, ATurnSetsTheWarpOnTheBiasAndTheCopyIsItsReflection) {
  scene::Sketch sketch = design("long-sleeve-tee.json");
  for (garment::PanelSpec& spec : sketch.panels)
    if (spec.id == "front") spec.grain = {GrainRule::kVertical, 45.0};
  const Body body = load_sketch_body(sketch);
  const Garment g = build_garment(sketch, BodySurface(body.mesh));
  const MaterialFrames frames = material_frames(g);
  int checked = 0;
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
    const GarmentPanel& panel = g.panels[static_cast<size_t>(g.face_panel(f))];
    if (panel.id != "front" && panel.id != "front.mirror") continue;
    const Eigen::Vector3d n = frames.normal.row(f).transpose();
    const Eigen::Vector3d up = (Eigen::Vector3d::UnitY() - n.y() * n).normalized();
    const Eigen::Vector3d warp = frames.warp.row(f).transpose();
    const double turn = std::atan2(up.cross(warp).dot(n), up.dot(warp)) / kDegree;
    EXPECT_NEAR(turn, panel.mirror_copy ? -45.0 : 45.0, 1e-9);
    EXPECT_NEAR(warp.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(frames.weft.row(f).dot(frames.warp.row(f)), 0.0, 1e-12);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace sd::garment
