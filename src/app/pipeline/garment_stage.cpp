#include "src/app/pipeline/garment_stage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "garment/body_surface.hpp"
#include "garment/sketch_inputs.hpp"

namespace sd::app {
namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

void check_mesh48(const meshing::Mesh48& m48) {
  const std::vector<std::string> problems = m48.validate();
  if (!problems.empty()) throw std::runtime_error("4-8 mesh check failed: " + problems.front());
}

}  // namespace

MeshedGarment mesh_garment(const scene::Sketch& sketch) {
  const auto body_start = std::chrono::steady_clock::now();
  garment::Body body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(body.mesh);
  const double body_ms = ms_since(body_start);
  const auto mesh_start = std::chrono::steady_clock::now();
  garment::Garment g = garment::build_garment(sketch, surface);
  const double meshing_ms = ms_since(mesh_start);

  std::vector<std::string> groups;
  std::vector<int> panel_group(g.panels.size());
  for (size_t p = 0; p < g.panels.size(); ++p) {
    auto it = std::find(groups.begin(), groups.end(), g.panels[p].group);
    if (it == groups.end()) it = groups.insert(groups.end(), g.panels[p].group);
    panel_group[p] = static_cast<int>(it - groups.begin());
  }
  meshing::Mesh48 m48 = meshing::Mesh48::from_quads(g.mesh);
  check_mesh48(m48);
  return {std::move(body), std::move(g), std::move(groups), std::move(panel_group),
          std::move(m48),  body_ms,      meshing_ms};
}

ImportedGarment import_garment(const scene::Sketch& sketch) {
  meshing::TriMesh triangles = garment::load_garment_mesh(sketch);
  meshing::Sqrt3Stats stats;
  meshing::Mesh48 m48 = [&] {
    try {
      return meshing::Mesh48::from_triangles_sqrt3(triangles, &stats);
    } catch (const meshing::Mesh48InputError& e) {
      sketch.fail("/garment_mesh",
                  fmt::format("the garment mesh cannot become a 4-8 mesh: {}", e.what()));
    }
  }();
  check_mesh48(m48);
  return {std::move(triangles), std::move(m48), stats};
}

}  // namespace sd::app
