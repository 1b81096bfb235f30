// `sketchdrape validate SKETCH`: checks a sketch file the way `mesh` would use it — fields,
// body, strokes on the body, curve network, panels, edge counts and the quad fill — and
// writes nothing.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <iostream>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/sketch_file.hpp"
#include "garment/sketch_inputs.hpp"
#include "meshing/mesh48.hpp"
#include "src/app/cli.hpp"

namespace sd::app {
namespace {

struct ValidateOptions {
  std::string sketch;
};

void run_validate(const ValidateOptions& options) {
  const garment::Sketch sketch = garment::load_sketch(options.sketch);
  if (sketch.garment_mesh) {
    const meshing::TriMesh mesh = garment::load_garment_mesh(sketch);
    try {
      (void)meshing::Mesh48::from_triangles_sqrt3(mesh);
    } catch (const meshing::Mesh48InputError& e) {
      sketch.fail("/garment_mesh", fmt::format("the garment mesh cannot become a 4-8 mesh: {}", e.what()));
    }
    std::cout << fmt::format("{}: ok (garment mesh: {} vertices, {} triangles)\n", sketch.file,
                             mesh.vertex_count(), mesh.face_count());
    return;
  }
  const garment::Body body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(body.mesh);
  const garment::Garment g = garment::build_garment(sketch, surface);
  int distortion = 0;
  for (const auto& p : g.panels) distortion += p.distortion;
  std::cout << fmt::format("{}: ok ({} curves, {} panels, {} quads, distortion {})\n", sketch.file,
                           sketch.curves.size(), g.panels.size(), g.mesh.face_count(), distortion);
}

}  // namespace

void add_validate_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<ValidateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "validate", "Check a sketch file (fields, body, curves on the body, panels, edge counts); "
                  "writes nothing");
  cmd->add_option("SKETCH", options->sketch, "Sketch file (format sketchdrape/1)")->required();
  cmd->callback([options] { run_validate(*options); });
}

}  // namespace sd::app
