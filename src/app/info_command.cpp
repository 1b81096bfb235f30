// `sketchdrape info BODY`: what a body file holds and how it will be normalised.

#include <fmt/format.h>

#include <iostream>
#include <nlohmann/json.hpp>

#include "garment/body.hpp"
#include "src/app/cli.hpp"

namespace sd::app {
namespace {

struct InfoOptions {
  std::string body;
  std::string up;
  double height = 0;
  double scale = 0;
  bool json = false;
};

nlohmann::json box_json(const meshing::BoundingBox& box) {
  return {{"min", {box.min.x(), box.min.y(), box.min.z()}},
          {"max", {box.max.x(), box.max.y(), box.max.z()}}};
}

void run_info(const InfoOptions& options) {
  garment::BodyOptions body_options;
  if (!options.up.empty()) body_options.up = garment::AxisDirection::parse(options.up);
  if (options.height > 0) body_options.height = options.height;
  if (options.scale > 0) body_options.scale = options.scale;
  const garment::Body body = garment::load_body(options.body, body_options);
  const meshing::TriMeshTopology topo = meshing::analyse_topology(body.mesh);
  const meshing::BoundingBox box = meshing::bounding_box(body.mesh);
  const garment::RawBodyInfo& raw = body.raw;

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
       {{"bounding_box", box_json(box)}, {"height_m", box.extent().y()}, {"up_axis", "+y"},
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
      raw.source, body.mesh.vertex_count(), body.mesh.face_count(), raw.meshes,
      b.extent().x(), b.extent().y(), b.extent().z(), b.min.x(), b.min.y(), b.min.z(),
      b.max.x(), b.max.y(), b.max.z(), raw.up.name(), raw.up_inferred ? "inferred" : "given",
      raw.facing.name(), raw.height, raw.scale, raw.scale_rule, box.extent().y(), box.min.x(),
      box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z(),
      topo.closed() ? "yes" : "no", topo.edge_manifold() ? "yes" : "no",
      topo.oriented() ? "yes" : "no", topo.components, topo.boundary_edges,
      topo.non_manifold_edges, topo.degenerate_faces);
  if (raw.flipped_inside_out)
    std::cout << fmt::format("orientation inside out in the file (volume {:.4g} units³): faces flipped\n",
                             raw.signed_volume);
  for (const std::string& warning : body.warnings) std::cout << "warning     " << warning << "\n";
}

}  // namespace

void add_info_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Describe a body mesh: size, up axis, topology, and how it will be normalised");
  cmd->add_option("BODY", options->body, "Body mesh file (any format assimp reads) or 'builtin'")
      ->required();
  cmd->add_option("--up", options->up, "The file's up axis (x, y, z, -x, ...); inferred if omitted");
  cmd->add_option("--height", options->height, "Scale the body to this height in metres")
      ->check(finite_range(0.1, 5.0));
  cmd->add_option("--scale", options->scale, "Metres per file unit")->check(finite_range(1e-9, 1e9));
  cmd->add_flag("--json", options->json, "Print one JSON object instead of text");
  cmd->callback([options] { run_info(*options); });
}

}  // namespace sd::app
