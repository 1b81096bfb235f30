#include "garment/body_clearance.hpp"

#include <array>
#include <unordered_map>

namespace sd::garment {
namespace {
// Samples per side of each of a quad's four triangles: a quarter of a 2.5 cm quad is about 9 mm,
// finer than the bulge of a knee or a thigh between two vertices on the offset surface.
constexpr int kSteps = 4;
}  // namespace

std::vector<PanelInsideBody> find_panels_inside_body(const Garment& garment,
                                                     const BodySurface& body, double tolerance) {
  const meshing::QuadMesh& mesh = garment.mesh;
  // Each vertex measured once.
  Eigen::VectorXd depth(mesh.vertex_count());
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    depth(v) = -body.signed_distance(mesh.vertices.row(v).transpose());
  std::vector<PanelInsideBody> panels(garment.panels.size());
  std::vector<std::vector<char>> counted(garment.panels.size());
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const int p = garment.face_panel(f);
    PanelInsideBody& out = panels[static_cast<size_t>(p)];
    out.panel = p;
    std::array<Eigen::Vector3d, 4> c;
    for (int k = 0; k < 4; ++k) c[static_cast<size_t>(k)] = mesh.vertices.row(mesh.faces(f, k));
    bool inside = false;
    const auto sample = [&](const Eigen::Vector3d& x, double d) {
      if (d <= tolerance) return;
      inside = true;
      if (d > out.deepest) out.deepest = d, out.where = x;
    };
    for (int k = 0; k < 4; ++k) {
      const int v = mesh.faces(f, k);
      sample(c[static_cast<size_t>(k)], depth(v));
      if (depth(v) > tolerance) {
        auto& seen = counted[static_cast<size_t>(p)];
        if (seen.empty()) seen.assign(static_cast<size_t>(mesh.vertex_count()), 0);
        if (!seen[static_cast<size_t>(v)]) seen[static_cast<size_t>(v)] = 1, ++out.vertices;
      }
    }
    // The 4-8 mesh the simulator drapes splits the quad at its centre into four triangles:
    // each sampled on a barycentric grid of kSteps per side (corners measured above).
    const Eigen::Vector3d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& a = c[static_cast<size_t>(k)];
      const Eigen::Vector3d& b = c[static_cast<size_t>((k + 1) % 4)];
      for (int i = 0; i <= kSteps; ++i)
        for (int j = 0; i + j <= kSteps; ++j) {
          if ((i == kSteps) || (j == kSteps) || (i == 0 && j == 0 && k > 0)) continue;
          const Eigen::Vector3d x = centre + (static_cast<double>(i) / kSteps) * (a - centre) +
                                    (static_cast<double>(j) / kSteps) * (b - centre);
          sample(x, -body.signed_distance(x));
        }
    }
    if (inside) ++out.quads;
  }
  std::vector<PanelInsideBody> found;
  for (const PanelInsideBody& p : panels)
    if (p.quads > 0) found.push_back(p);
  return found;
}

}  // namespace sd::garment
