// `sketchdrape info BODY`: what a body file holds and how it will be normalised.

#include <fmt/format.h>

#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "garment/body.hpp"
#include "garment/body_facing.hpp"
#include "garment/body_landmarks.hpp"
#include "garment/sketch_error.hpp"
#include "src/app/commands/cli.hpp"

namespace sd::app {
namespace {

struct InfoOptions {
  std::string body;
  BodyFileOptions reading;  // --up, --facing, --height, --scale
  bool json = false;
  std::vector<double> slices;  // heights, m (normalised frame)
};

nlohmann::json box_json(const meshing::BoundingBox& box) {
  return {{"min", {box.min.x(), box.min.y(), box.min.z()}},
          {"max", {box.max.x(), box.max.y(), box.max.z()}}};
}

void run_info(const InfoOptions& options) {
  const garment::Body body = garment::load_body(options.body, options.reading.body_options());
  const meshing::TriMeshTopology topo = meshing::analyse_topology(body.mesh);
  const meshing::BoundingBox box = meshing::bounding_box(body.mesh);
  const garment::RawBodyInfo& raw = body.raw;
  // A slice outside the figure has no outline: a mistake (a height in cm, or in the file's own
  // frame), not an empty answer.
  for (const double y : options.slices) {
    if (y < box.min.y() || y > box.max.y())
      throw std::invalid_argument(
          fmt::format("--slice {:g} is outside the body, which spans {:.3f} .. {:.3f} m in the "
                      "normalised frame "
                      "(feet at the bottom, metres; see docs/bodies.md)",
                      y, box.min.y(), box.max.y()));
  }

  nlohmann::json out = {
      {"source", raw.source},
      {"meshes", raw.meshes},
      {"vertices", body.mesh.vertex_count()},
      {"triangles", body.mesh.face_count()},
      {"raw",
       {{"bounding_box", box_json(raw.box)},
        {"height", raw.height},
        {"up_axis", raw.up.name()},
        {"up_axis_inferred", raw.up_inferred},
        {"facing", raw.facing.name()}}},
      {"normalisation", {{"scale", raw.scale}, {"scale_rule", raw.scale_rule}}},
      {"normalised",
       {{"bounding_box", box_json(box)},
        {"height_m", box.extent().y()},
        {"up_axis", "+y"},
        {"facing", "+z"}}},
      {"topology",
       {{"closed", topo.closed()},
        {"edge_manifold", topo.edge_manifold()},
        {"consistently_oriented", topo.oriented()},
        {"components", topo.components},
        {"boundary_edges", topo.boundary_edges},
        {"non_manifold_edges", topo.non_manifold_edges},
        {"degenerate_faces", topo.degenerate_faces},
        {"signed_volume_raw", raw.signed_volume},
        {"flipped_inside_out", raw.flipped_inside_out}}},
      {"warnings", body.warnings},
  };
  // Landmarks, when the body looks like a standing figure (a mannequin's torso alone has none).
  std::optional<garment::BodyLandmarks> landmarks;
  std::optional<garment::FacingCues> facing;  // which way it faces, from its head and feet
  std::string landmark_problem;
  try {
    landmarks = garment::find_landmarks(body.mesh);
  } catch (const std::runtime_error& e) {
    landmark_problem = e.what();
    // Stood on its head (trial 40, P3), or turned a quarter round: then it faces along the
    // file's third axis, the one neither up nor the facing it was read with (trial 39, P14).
    if (const std::string upside = garment::upside_down_advice(body); !upside.empty()) {
      landmark_problem = upside + "; " + landmark_problem;
    } else if (garment::looks_turned(body.mesh)) {
      const int third = 3 - raw.up.axis - raw.facing.axis;
      landmark_problem +=
          fmt::format(": try --facing {} or {}", garment::AxisDirection{third, 1}.name(),
                      garment::AxisDirection{third, -1}.name());
    }
  }
  if (landmarks) {
    nlohmann::json points = nlohmann::json::object();
    for (const garment::Landmark& l : landmarks->points)
      points[l.name] = {l.position.x(), l.position.y(), l.position.z()};
    out["landmarks"] = points;
    out["girths_m"] = {{"chest", landmarks->chest_girth},
                       {"waist", landmarks->waist_girth},
                       {"hips", landmarks->hip_girth}};
    out["landmark_doubts"] = landmarks->doubts;
    facing = garment::facing_cues(body.mesh, *landmarks);
    const auto cue_json = [](const garment::FacingCue& c) {
      return nlohmann::json{
          {"found", c.found}, {"ahead_m", c.ahead}, {"behind_m", c.behind}, {"lean", c.lean()}};
    };
    out["facing_cues"] = {{"head", cue_json(facing->head)},
                          {"feet", cue_json(facing->feet)},
                          {"backwards", facing->backwards()}};
  } else {
    out["landmarks"] = nullptr;
    out["landmarks_problem"] = landmark_problem;
  }
  // Which part of the figure an outline of the slice at height y is: the one spanning x = 0 is
  // the torso (the head above the neck's base); beside it, arms above the crotch and legs below.
  // Without landmarks only the side is known.
  const auto part_of = [&](const garment::SliceOutline& o, double y) -> std::string {
    const garment::Landmark* crotch = landmarks ? landmarks->find("crotch") : nullptr;
    const garment::Landmark* neck = landmarks ? landmarks->find("neck_base") : nullptr;
    if (o.min.x() <= 0 && o.max.x() >= 0) return neck && y > neck->position.y() ? "head" : "torso";
    const std::string side = o.centroid.x() > 0 ? "left" : "right";
    if (!crotch) return side + " side";
    return side + (y < crotch->position.y() ? " leg" : " arm");
  };
  nlohmann::json slices = nlohmann::json::array();
  std::string slice_text;
  for (const double y : options.slices) {
    nlohmann::json outlines = nlohmann::json::array();
    slice_text += fmt::format("slice y = {:.3f} m:\n", y);
    for (const garment::SliceOutline& o : garment::slice_body(body.mesh, y)) {
      const std::string part = part_of(o, y);
      outlines.push_back({{"part", part},
                          {"centroid", {o.centroid.x(), o.centroid.y(), o.centroid.z()}},
                          {"x", {o.min.x(), o.max.x()}},
                          {"z", {o.min.z(), o.max.z()}},
                          {"girth", o.girth}});
      slice_text += fmt::format(
          "  {:<10} x {:.3f} .. {:.3f}, z {:.3f} .. {:.3f} m, centre ({:.3f}, "
          "{:.3f}), girth {:.3f} m\n",
          part, o.min.x(), o.max.x(), o.min.z(), o.max.z(), o.centroid.x(), o.centroid.z(),
          o.girth);
    }
    slices.push_back({{"y", y}, {"outlines", outlines}});
  }
  if (!options.slices.empty()) out["slices"] = slices;
  if (options.json) {
    std::cout << out.dump(2) << "\n";
    return;
  }
  const auto& b = raw.box;
  std::cout << fmt::format(
      "body        {}\n"
      "vertices    {}\ntriangles   {}\nmeshes      {}\n"
      "raw file    {:.4g} x {:.4g} x {:.4g} units, bbox [{:.4g} {:.4g} {:.4g}] .. [{:.4g} {:.4g} "
      "{:.4g}]\n"
      "up axis     {} ({}), facing {}, height {:.4g} units\n"
      "normalised  scale {:.6g} ({}), height {:.3f} m, +y up, facing +z, feet at y = 0\n"
      "            bbox [{:.3f} {:.3f} {:.3f}] .. [{:.3f} {:.3f} {:.3f}] m\n"
      "topology    closed {}, edge-manifold {}, oriented {}, {} component(s), {} boundary "
      "edge(s), {} non-manifold edge(s), {} degenerate face(s)\n",
      garment::printable(raw.source), body.mesh.vertex_count(), body.mesh.face_count(), raw.meshes,
      b.extent().x(), b.extent().y(), b.extent().z(), b.min.x(), b.min.y(), b.min.z(), b.max.x(),
      b.max.y(), b.max.z(), raw.up.name(), raw.up_inferred ? "inferred" : "given",
      raw.facing.name(), raw.height, raw.scale, raw.scale_rule, box.extent().y(), box.min.x(),
      box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z(), topo.closed() ? "yes" : "no",
      topo.edge_manifold() ? "yes" : "no", topo.oriented() ? "yes" : "no", topo.components,
      topo.boundary_edges, topo.non_manifold_edges, topo.degenerate_faces);
  if (raw.flipped_inside_out)
    std::cout << fmt::format(
        "orientation inside out in the file (volume {:.4g} units³): faces flipped\n",
        raw.signed_volume);
  for (const std::string& warning : body.warnings)
    std::cout << "warning     " << garment::printable(warning) << "\n";
  std::cout << slice_text;
  if (!landmarks) {
    std::cout << fmt::format("landmarks   none: {}\n", garment::printable(landmark_problem));
    return;
  }
  std::cout << "landmarks   (m, normalised frame: x to the body's left, y up, z forward)\n";
  for (const garment::Landmark& l : landmarks->points)
    std::cout << fmt::format("  {:<15} [{:7.3f} {:7.3f} {:7.3f}]\n", l.name, l.position.x(),
                             l.position.y(), l.position.z());
  std::cout << fmt::format(
      "girths      chest {:.3f} m, waist {:.3f} m, hips {:.3f} m (convex hull of "
      "the torso's slice)\n",
      landmarks->chest_girth, landmarks->waist_girth, landmarks->hip_girth);
  // The facing the figure shows (docs/bodies.md, Normalisation): a body loaded with a given
  // facing that turns it round is refused before this; one that breaks its up axis's convention
  // unasked is told here.
  std::string shown;
  if (facing->head.found)
    shown = fmt::format("its head reaches {:.1f} cm forward of the neck, {:.1f} cm back",
                        100 * facing->head.ahead, 100 * facing->head.behind);
  if (facing->feet.found)
    shown +=
        fmt::format("{}its toes {:.1f} cm forward of the ankles, heels {:.1f} cm back",
                    shown.empty() ? "" : "; ", 100 * facing->feet.ahead, 100 * facing->feet.behind);
  if (shown.empty()) shown = "not measured (no head above the neck, no feet)";
  std::cout << fmt::format("facing      {}\n", shown);
  if (facing->backwards())
    std::cout << fmt::format(
        "warning     the figure faces backwards (its face{} behind): give --facing {} (in a "
        "sketch, \"body\": {{\"facing\": \"{}\"}})\n",
        facing->feet.found ? " and toes" : "",
        garment::AxisDirection{raw.facing.axis, -raw.facing.sign}.name(),
        garment::AxisDirection{raw.facing.axis, -raw.facing.sign}.name());
  for (const std::string& doubt : landmarks->doubts)
    std::cout << "warning     the landmarks look wrong: " << doubt
              << "; is this a standing human figure, feet down, facing +z after normalisation? "
                 "(docs/bodies.md, \"Landmarks\")\n";
}

}  // namespace

void add_info_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Describe a body mesh: size, up axis, topology, and how it will be normalised");
  cmd->add_option("BODY", options->body, "Body mesh file (any format assimp reads) or 'builtin'")
      ->required();
  add_body_file_options(*cmd, options->reading);
  cmd->add_flag("--json", options->json, "Print one JSON object instead of text");
  cmd->add_option("--slice", options->slices,
                  "Also print the body's outlines at this height (m, normalised frame; repeat for "
                  "several): where legs, arms and torso are, to place curves")
      ->check(finite_range(-1e3, 1e3));
  cmd->callback([options] { run_info(*options); });
}

}  // namespace sd::app
