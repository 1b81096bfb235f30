#include "src/app/pipeline/seam_ease_warnings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace sd::app {

std::vector<std::string> seam_ease_warnings(const scene::Sketch& sketch,
                                            const garment::Garment& garment) {
  std::vector<std::string> warnings;
  const meshing::QuadMesh& mesh = garment.mesh;
  // The panels on each side of every mesh edge (by its lower, higher vertex).
  std::map<std::pair<int, int>, std::vector<int>> sides;
  for (Eigen::Index q = 0; q < mesh.face_count(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = mesh.faces(q, k), b = mesh.faces(q, (k + 1) % 4);
      sides[{std::min(a, b), std::max(a, b)}].push_back(garment.face_panel(static_cast<int>(q)));
    }
  // Per seam curve of an original (not a mirror copy) and pair of panels: its length, m.
  std::map<std::pair<std::string, std::pair<int, int>>, double> seams;
  for (const auto& [edge, curve] : garment.edge_curve) {
    if (curve.ends_with(".mirror")) continue;
    const auto found = sides.find(edge);
    if (found == sides.end() || found->second.size() != 2) continue;
    int a = found->second[0], b = found->second[1];
    if (a == b) continue;
    if (garment.panels[static_cast<size_t>(a)].mirror_copy &&
        garment.panels[static_cast<size_t>(b)].mirror_copy)
      continue;
    if (a > b) std::swap(a, b);
    seams[{curve, {a, b}}] +=
        (mesh.vertices.row(edge.first) - mesh.vertices.row(edge.second)).norm();
  }
  for (const auto& [key, length] : seams) {
    const garment::GarmentPanel& pa = garment.panels[static_cast<size_t>(key.second.first)];
    const garment::GarmentPanel& pb = garment.panels[static_cast<size_t>(key.second.second)];
    if (!pa.ease.isotropic() || !pb.ease.isotropic()) continue;
    const double ea = pa.ease.warp, eb = pb.ease.warp;
    const double difference = std::abs(ea - eb) / std::max(ea, eb);
    if (difference <= kSeamEaseLimit) continue;
    // The longer and the shorter side; the path of the panel whose ease is further from 1 (the
    // one the designer changed), named by the original's id.
    const garment::GarmentPanel& longer = ea > eb ? pa : pb;
    const garment::GarmentPanel& shorter = ea > eb ? pb : pa;
    const auto base = [](const std::string& id) {
      return id.ends_with(".mirror") ? id.substr(0, id.size() - 7) : id;
    };
    const garment::GarmentPanel& changed =
        std::abs(pa.ease.warp - 1) >= std::abs(pb.ease.warp - 1) ? pa : pb;
    const garment::PanelSpec* spec = sketch.find_panel(base(changed.id));
    const std::string path = spec ? spec->json_path + "/ease" : "/panels";
    // Eases within the limit: the longer side down to at most, or the shorter up to at least.
    const double longest_ok = std::floor(shorter.ease.warp / (1 - kSeamEaseLimit) * 100) / 100;
    const double shortest_ok = std::ceil(longer.ease.warp * (1 - kSeamEaseLimit) * 100) / 100;
    warnings.push_back(fmt::format(
        "{}: {}: panels '{}' (ease {:g}) and '{}' (ease {:g}) are sewn along curve '{}' ({:.0f} "
        "mm), whose two sides rest {:.1f} % ({:.0f} mm) apart in length: the simulator cannot "
        "ease the longer side in as ripples a few millimetres wide, so the seam holds it "
        "squeezed by about half of that and the other side stretched by the other half, and "
        "past {:g} % the cloth at such a seam may never come to rest (a strapless dress with "
        "its bodice at 0.95 sewn to a skirt at 1 still moved at 4 cm/s under that seam after 8 "
        "s). Keep the eases of panels sewn together within {:g} % of each other: give '{}' an "
        "ease of at most {:g}, or '{}' at least {:g}; for fullness on purpose gather it "
        "({{\"weft\": ...}}, docs/sketch-format.md, \"Gathers\")",
        sketch.file, path, base(pa.id), ea, base(pb.id), eb, base(key.first), 1e3 * length,
        100 * difference, 1e3 * length * difference, 100 * kSeamEaseLimit, 100 * kSeamEaseLimit,
        base(longer.id), longest_ok, base(shorter.id), shortest_ok));
  }
  return warnings;
}

}  // namespace sd::app
