// `sketchdrape mesh SKETCH [-o DIR]`: the sketch's panels as one stitched quad mesh
// (garment.obj or .glb, one group per panel), its 4-8 triangle mesh (garment48.obj), a report
// (report.json: per panel sides, counts, distortion, quality; totals) and, when the file asks
// for images, PNGs of the panels on the body (of a sheet's or an imported garment's triangles in
// one colour). No simulation. All files appear together or not
// at all.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "garment/garment_mesh.hpp"
#include "garment/unused_curves.hpp"
#include "meshing/mesh48.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/cloth_scene.hpp"
#include "src/app/pipeline/garment_stage.hpp"
#include "src/app/pipeline/mesh_export.hpp"
#include "src/app/pipeline/pattern_export.hpp"
#include "src/app/pipeline/preview_images.hpp"
#include "src/app/pipeline/quality_warnings.hpp"
#include "src/app/pipeline/sketch_checks.hpp"
#include "src/render/previews.hpp"
#include "src/render/scene.hpp"

namespace sd::app {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct MeshOptions {
  std::string sketch;
  std::string out = ".";
  bool strict = false;
};

std::string obj_48(const meshing::Mesh48& m48, const std::vector<int>& block_group,
                   const std::vector<std::string>& groups) {
  const meshing::Mesh48Arrays a = m48.arrays();
  ExportMesh mesh;
  mesh.vertices = a.rest_positions;
  mesh.faces = a.faces;
  mesh.group_names = groups.empty() ? std::vector<std::string>{"garment"} : groups;
  mesh.face_groups.resize(static_cast<size_t>(a.faces.rows()), 0);
  for (Eigen::Index f = 0; f < a.faces.rows(); ++f) {
    const int block = a.face_block(f);
    if (block >= 0 && block < static_cast<int>(block_group.size()))
      mesh.face_groups[static_cast<size_t>(f)] = block_group[static_cast<size_t>(block)];
  }
  return to_obj(mesh, "garment48");
}

nlohmann::json quality_json(const meshing::QuadQuality& q) {
  return {{"min_angle_deg", q.min_angle_deg},
          {"max_angle_deg", q.max_angle_deg},
          {"max_aspect_ratio", q.max_aspect_ratio},
          {"scaled_jacobian_min", q.scaled_jacobian_min},
          {"scaled_jacobian_mean", q.scaled_jacobian_mean},
          {"inverted_quads", q.inverted_quads}};
}

void run_mesh(const MeshOptions& options) {
  const auto start = Clock::now();
  const scene::Sketch sketch = scene::load_sketch(options.sketch);
  check_sketch(sketch);  // the fabrics and settings `run` would refuse, refused here too
  check_output_folder(options.out);
  const std::filesystem::path dir(options.out);
  StagedOutputs outputs;
  outputs.keep(sketch.file);
  if (sketch.garment_mesh) outputs.keep(sketch.resolve(*sketch.garment_mesh));
  if (sketch.body.mesh != "builtin") outputs.keep(sketch.resolve(sketch.body.mesh));
  nlohmann::json report = {{"format", "sketchdrape/1 mesh report"}, {"sketch", sketch.file}};
  // The scene `validate` and `run` build, with every check they make (pin_above, the fabric, a
  // flat rest's flattening, the body's poses, the drape's size): `mesh` refuses the same files
  // (trial 35: "pin_above": 2.5 was meshed with exit 0 and refused by validate).
  const ClothScene scene = build_cloth_scene_within_limits(sketch);
  // The pictures the file asks for of a cloth without panels (a sheet, an imported garment): in
  // one colour, its triangles' edges as the wireframe, over the body when the scene has one. They
  // were silently left out before (trial 42, P11).
  const auto stage_triangle_images = [&](const meshing::TriMesh& cloth) {
    if (sketch.output.images.empty()) return;
    const PreviewCloth preview{cloth, {}, render::triangle_edges(cloth), {}, {}};
    stage_preview_images(sketch.output.images, sketch.output.wireframe,
                         scene.body ? &scene.body->mesh : nullptr, preview, "garment", dir,
                         outputs);
  };

  if (sketch.sheet) {
    // A sheet scene: its grid of triangles is the fixed mesh `run` simulates (a sheet that asks
    // for adaptive detail drapes on the 4-8 mesh of its quads instead).
    ExportMesh mesh{scene.input.rest_positions, scene.input.triangles, {}, {"sheet"}};
    outputs.stage(dir / sketch.output.mesh, sketch.output.mesh.ends_with(".glb")
                                                ? to_glb(mesh, "sheet")
                                                : to_obj(mesh, "sheet"));
    report["sheet"] = {{"columns", sketch.sheet->columns}, {"rows", sketch.sheet->rows}};
    report["totals"] = {{"vertices", scene.input.rest_positions.rows()},
                        {"triangles", scene.input.triangles.rows()},
                        {"pinned_vertices", scene.pinned.size()}};
    meshing::TriMesh cloth;
    cloth.vertices = scene.input.rest_positions;
    cloth.faces = scene.input.triangles;
    stage_triangle_images(cloth);
    if (sketch.output.report) outputs.stage(dir / "report.json", report.dump(2) + "\n");
    outputs.commit();
    spdlog::info("meshed {} → {} (a sheet of {} triangles)", sketch.file, dir.string(),
                 scene.input.triangles.rows());
    return;
  }

  if (sketch.garment_mesh) {
    // An imported triangle garment: the √3 conversion gives its 4-8 mesh (as `run` drapes it).
    const ImportedGarment imported = import_garment(sketch);
    const meshing::TriMesh& tris = imported.triangles;
    const meshing::Sqrt3Stats& stats = imported.stats;
    const meshing::Mesh48& m48 = imported.mesh48;
    ExportMesh mesh{tris.vertices, tris.faces, {}, {"garment"}};
    outputs.stage(dir / sketch.output.mesh, sketch.output.mesh.ends_with(".glb")
                                                ? to_glb(mesh, "garment")
                                                : to_obj(mesh, "garment"));
    outputs.stage(dir / "garment48.obj", obj_48(m48, {}, {}));
    report["garment_mesh"] = sketch.resolve(*sketch.garment_mesh).string();
    report["totals"] = {{"vertices", tris.vertex_count()},
                        {"triangles", tris.face_count()},
                        {"file_faces", imported.file_faces},
                        {"blocks_48", stats.blocks},
                        {"boundary_blocks_48", stats.boundary_blocks},
                        {"unswapped_blocks_48", stats.unswapped_blocks},
                        {"triangles_48", m48.triangle_count()}};
    stage_triangle_images(tris);
    if (sketch.output.report) outputs.stage(dir / "report.json", report.dump(2) + "\n");
    outputs.commit();
    spdlog::info("meshed {} → {} ({} triangles, {} 4-8 blocks)", sketch.file, dir.string(),
                 tris.face_count(), stats.blocks);
    return;
  }

  // The garment as `run` drapes it: body, stitched quads, panel groups, checked 4-8 mesh.
  const garment::Body& body = *scene.body;
  const garment::Garment& g = *scene.garment;
  const double body_ms = scene.body_ms;
  const double mesh_ms = scene.meshing_ms;
  const std::vector<garment::QualityWarning> warnings = quality_warnings(g, sketch, body);

  // Quad mesh with one group per panel (joined panels share their join's group): the scene's
  // group of each quad.
  const std::vector<std::string>& groups = scene.group_names;
  ExportMesh quads{g.mesh.vertices, g.mesh.faces, {}, groups};
  for (Eigen::Index f = 0; f < scene.face_group.size(); ++f)
    quads.face_groups.push_back(scene.face_group(f));
  outputs.stage(dir / sketch.output.mesh, sketch.output.mesh.ends_with(".glb")
                                              ? to_glb(quads, "garment")
                                              : to_obj(quads, "garment"));

  const meshing::Mesh48& m48 = *scene.mesh48;
  const std::vector<int> block_group(scene.face_group.data(),
                                     scene.face_group.data() + scene.face_group.size());
  outputs.stage(dir / "garment48.obj", obj_48(m48, block_group, groups));

  nlohmann::json panels = nlohmann::json::array();
  int distortion = 0, irregular = 0;
  double area = 0;
  for (const garment::GarmentPanel& p : g.panels) {
    panels.push_back({{"id", p.id},
                      {"group", p.group},
                      {"fabric", p.fabric},
                      {"body_part", p.body_part},
                      {"mirror_copy", p.mirror_copy},
                      {"ease", ease_json(p.ease)},
                      {"sides", p.side_counts.size()},
                      {"side_counts", p.side_counts},
                      {"curves", p.curves},
                      {"partition", p.partition},
                      {"distortion", p.distortion},
                      {"irregular_vertices", p.irregular_vertices},
                      {"quads", p.faces},
                      {"area_m2", p.area},
                      {"fit", p.fit},
                      {"span_gap_m", p.span_gap},
                      {"grain", p.grain},
                      {"grain_axis", {p.grain_axis.x(), p.grain_axis.y(), p.grain_axis.z()}},
                      {"grain_turn_deg", p.grain_turn_deg},
                      {"quality", quality_json(p.quality)}});
    distortion += p.distortion;
    irregular += p.irregular_vertices;
    area += p.area;
  }
  report["warnings"] = warnings_json(warnings);
  // The body's repairs and defects (an open body, ...): the sentences the terminal showed.
  report["body"] = {{"mesh", sketch.body.mesh},
                    {"source", body.raw.source},
                    {"triangles", body.mesh.face_count()},
                    {"warnings", body.warnings}};
  report["panels"] = panels;
  report["totals"] = {{"panels", g.panels.size()},          {"vertices", g.mesh.vertex_count()},
                      {"quads", g.mesh.face_count()},       {"triangles_48", m48.triangle_count()},
                      {"seam_edges", g.seam_edges},         {"curve_pieces", g.curve_pieces},
                      {"parity_changes", g.parity_changes}, {"distortion", distortion},
                      {"irregular_vertices", irregular},    {"area_m2", area}};

  // The flat sewing pattern, when the file asks for it.
  if (sketch.output.pattern) {
    const PatternSheet sheet = build_pattern_sheet(
        sketch, g, *sketch.output.pattern, scene.flat_pattern ? &*scene.flat_pattern : nullptr,
        scene.flattening_ms, &body);
    stage_pattern(sheet, dir, outputs);
    report["pattern"] = pattern_summary(sheet);
  }

  // Images: the 4-8 triangles with each quad's panel colour and the quad edges as wireframe.
  const auto image_start = Clock::now();
  if (!sketch.output.images.empty()) {
    meshing::TriMesh cloth;
    cloth.vertices = g.mesh.vertices;
    cloth.faces = render::triangulate_quads(g.mesh.faces);
    Eigen::VectorXi tri_panel(2 * g.face_panel.size());
    for (Eigen::Index f = 0; f < g.face_panel.size(); ++f)
      tri_panel(2 * f) = tri_panel(2 * f + 1) = g.face_panel(f);
    const PreviewCloth preview{cloth, tri_panel, render::quad_edges(g.mesh.faces), {}, {}};
    stage_preview_images(sketch.output.images, sketch.output.wireframe, &body.mesh, preview,
                         "garment", dir, outputs);
  }
  report["timing_ms"] = {{"body", body_ms},
                         {"meshing", mesh_ms},
                         {"images", ms_since(image_start)},
                         {"total", ms_since(start)}};
  if (sketch.output.report) outputs.stage(dir / "report.json", report.dump(2) + "\n");
  outputs.commit();
  if (const std::string notice =
          stale_outputs_notice(dir, stale_outputs(dir, outputs.paths_and_inputs()));
      !notice.empty())
    spdlog::warn("{}", notice);
  spdlog::info("meshed {} → {}: {} panels, {} quads, distortion {} ({:.0f} ms meshing)",
               sketch.file, dir.string(), g.panels.size(), g.mesh.face_count(), distortion,
               mesh_ms);
  if (const std::string failure =
          strict_failure(sketch.file, warnings, garment::unused_curve_warnings(sketch, g).size(),
                         garment::half_mirrored_warnings(sketch, g).size());
      options.strict && !failure.empty())
    throw std::runtime_error(failure);
}

}  // namespace

void add_mesh_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<MeshOptions>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "Mesh a sketch file's panels into one stitched garment (quad and 4-8 meshes, report, "
      "images); no simulation");
  cmd->add_option("SKETCH", options->sketch, "Sketch file (format sketchdrape/1)")->required();
  cmd->add_option("-o,--out", options->out, "Output directory (created if needed)")
      ->check(non_empty_path());
  cmd->add_flag("--strict", options->strict,
                "Exit with code 1 when the quality gate warns or a curve is in no panel (the "
                "outputs are still written)");
  cmd->callback([options] { run_mesh(*options); });
}

}  // namespace sd::app
