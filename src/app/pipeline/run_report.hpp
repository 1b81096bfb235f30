#pragma once
// What `sketchdrape run` reports (report.json, docs/cli.md): a plain struct the drape fills as it
// goes, written as JSON in one place (run_report_json). The keys and values are the file's
// format: tests and docs read them.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "meshing/slice_dent.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/cloth_model.hpp"
#include "sim/simulation.hpp"
#include "src/app/pipeline/cloth_scene.hpp"

namespace sd::app {

// The garment's meshing as the drape report shows it (absent for a sheet or an imported mesh).
struct MeshingSummary {
  struct Panel {
    std::string id;
    std::size_t sides = 0;
    int distortion = 0;
    int irregular_vertices = 0;
    std::string partition;
    int quads = 0;
  };
  int distortion = 0;  // summed over the panels
  int irregular_vertices = 0;
  Eigen::Index quads = 0;
  double meshing_ms = 0;
  std::vector<Panel> panels;
};

// The scene's garment summed up; nullopt when the scene has none.
std::optional<MeshingSummary> meshing_summary(const ClothScene& scene);

// How far a group of the drape is from its rest shape: per triangle strain =
// max(σ₁ − 1, 1 − σ₂) of its deformation gradient; max and rest-area-weighted mean. Apart, the
// largest stretch σ₁ − 1 alone (compression is cloth buckling finer than the mesh, stretch is
// cloth pulled) and the centre of that triangle, m.
struct GroupStrain {
  std::string group;
  double max = 0;
  double mean = 0;
  double stretch_max = 0;
  Eigen::Vector3d stretch_at = Eigen::Vector3d::Zero();
};

// Per group (group_names; triangle_group: #F of the model, index into group_names).
std::vector<GroupStrain> group_strains(const sim::ClothModel& model,
                                       const Eigen::MatrixX3d& positions,
                                       const Eigen::VectorXi& triangle_group,
                                       const std::vector<std::string>& group_names);

// The body's motion over the drape.
struct BodyMotionSummary {
  std::string type;                  // "arms-lowering" | "poses"
  double start = 0;                  // s
  double end = 0;                    // s
  std::optional<std::size_t> poses;  // "poses": how many keyframes the file gives
  std::optional<double> degrees;     // "arms-lowering": the rotation at the end
};

struct RunReport {
  std::string sketch;  // the file, as given
  std::string scene;   // "garment", "imported garment" or "sheet"
  std::string fabric;
  std::optional<std::string> body;  // the body's source; none for a sheet without a body
  std::size_t pinned_vertices = 0;
  std::optional<MeshingSummary> meshing;
  // An imported garment: the file ("garment_mesh"), its own vertices, triangles and faces as
  // written, and the √3 4-8 mesh's level-0 vertices and triangles that were draped.
  std::optional<nlohmann::json> imported;
  std::string bending;      // the bend model that ran
  std::string compression;  // the membrane's compression model that ran
  // A horizontal disc held at its centre: the Cusick drape test's measures (DC, nodes).
  std::optional<nlohmann::json> cusick;
  // A horizontal strip held by a clamp "top:N": the cantilever test's measures (chord angle,
  // bending length).
  std::optional<nlohmann::json> cantilever;
  std::string rest_shape;  // "shaped", "flat" or "flat and shaped"
  sim::SimulationSettings settings;
  // The automatic rule's reason, when the file left the solver or the step to it ("auto").
  std::optional<std::string> automatic;
  sim::SimulationReport simulation;
  std::optional<sim::AdaptiveReport> adaptive;  // when the cloth adapted
  std::vector<GroupStrain> strain;              // against the rest shape (the pattern when flat)
  int self_intersections_final = 0;             // counted whether or not self-collision was on
  // Garments reaching below the crotch: the dent between supports (a skirt pulled between the
  // legs), over the slices from 10 % of the garment's height to slice_dent_to (at most 60 %,
  // never above the crotch: higher up a sleeve beside the torso reads as a dent).
  std::optional<meshing::SliceDent> slice_dent;
  double slice_dent_to = 0.6;
  // Garments on a body: how far (m) the cloth's centre of mass ended below where it was drawn
  // (negative: above), from the gravitational potential of the first and last steps. A garment
  // nothing grips (a loose strapless top) slides down until something holds it.
  std::optional<double> settled_drop;
  std::optional<nlohmann::json> pattern;  // pattern_summary, when the file asks
  // The run's warnings about the drape (not at rest at the end, settled below where drawn),
  // each the sentence the terminal shows.
  std::vector<std::string> warnings;
  // The quality gate's warnings (`validate`'s mesh quality warnings, which --strict counts), also
  // among `warnings`.
  int quality_warnings = 0;
  std::vector<std::string> images;
  std::size_t frames = 0;
  std::optional<BodyMotionSummary> body_motion;
  double images_s = 0;  // wall time writing images and frames
  double total_s = 0;   // wall time of the whole command
};

// report.json's contents.
nlohmann::json run_report_json(const RunReport& report);

// The top of a garment's slice-dent slices (RunReport::slice_dent), as a fraction of the
// draped garment's height above its lowest point `low` (its highest: `high`): 60 %, lowered to
// the body's crotch when there is one. Nothing for a garment that ends less than 5 cm below the
// crotch (a top: only a sleeve and the torso would be there to dent).
std::optional<double> slice_dent_top(double low, double high, std::optional<double> crotch);

}  // namespace sd::app
