// `sketchdrape fill --sides 5,6,3,6,4`: fills an n-sided region with quads and reports its
// distortion and quality; optionally writes the patch as OBJ and as a flat wireframe PNG.
// The region's corners lie on the unit circle at angles proportional to the edge counts before
// them, with straight sides (circular arcs for n = 2), so side lengths follow the counts.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <sstream>
#include <string>

#include "garment/sketch_ranges.hpp"
#include "meshing/patch_fill.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/render/image.hpp"
#include "src/render/previews.hpp"
#include "src/render/renderer.hpp"

namespace sd::app {
namespace {

struct FillOptions {
  std::string sides;
  bool json = false;
  std::string obj;
  std::string png;
  std::string size = "800x800";
  int relax = meshing::FillGeometryOptions{}.relax_iterations;
};

class FillUsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

std::vector<int> parse_sides(const std::string& text) {
  std::vector<int> counts;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size())
      throw FillUsageError("--sides must be edge counts separated by commas, like 5,6,3,6,4; '" +
                           item + "' is not a whole number");
    counts.push_back(value);
  }
  if (counts.empty()) throw FillUsageError("--sides needs at least two edge counts, like 4,4");
  // A region of B boundary edges holds up to (B/4)² quads (garment/sketch_ranges.hpp).
  double total = 0;
  for (int c : counts) total += std::max(c, 0);
  if (garment::estimated_quads(total) > garment::kMaxFillQuads)
    throw FillUsageError(fmt::format(
        "--sides: {:.0f} boundary edges make up to {:.3g} quads, more than the {:.0f} this "
        "program fills; at most {:.0f} edges in all",
        total, garment::estimated_quads(total), garment::kMaxFillQuads,
        4 * std::sqrt(garment::kMaxFillQuads)));
  return counts;
}

// Boundary polylines: corners on the unit circle, straight sides (two arcs when n = 2).
std::vector<Eigen::MatrixX3d> region_sides(const std::vector<int>& counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  auto on_circle = [&](double position) {
    const double angle = 2 * std::numbers::pi * position / total + std::numbers::pi / 2;
    return Eigen::RowVector3d(std::cos(angle), std::sin(angle), 0.0);
  };
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    const int points = counts.size() == 2 ? std::max(count, 1) * 8 + 1 : 2;
    Eigen::MatrixX3d polyline(points, 3);
    for (int k = 0; k < points; ++k)
      polyline.row(k) = counts.size() == 2
                            ? on_circle(start + static_cast<double>(count) * k / (points - 1))
                            : on_circle(start + count * k);
    polyline.row(points - 1) = on_circle(start + count);
    sides.push_back(polyline);
    start += count;
  }
  // Exactly shared corners.
  for (size_t i = 0; i < sides.size(); ++i)
    sides[i].bottomRows<1>() = sides[(i + 1) % sides.size()].topRows<1>();
  return sides;
}

// Quads touching an irregular vertex are tinted, so a reader sees where the distortion is.
Eigen::MatrixX3f quad_colours(const meshing::FilledPatch& patch) {
  const auto& mesh = patch.mesh;
  const Eigen::VectorXi valence = meshing::vertex_valences(mesh);
  Eigen::VectorXi regular = Eigen::VectorXi::Constant(mesh.vertices.rows(), 4);
  for (const int v : meshing::boundary_loop(mesh)) regular(v) = 3;
  for (const int v : patch.topology.corner_vertices()) regular(v) = 2;
  Eigen::MatrixX3f colours(mesh.faces.rows(), 3);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    int deviation = 0;
    for (int k = 0; k < 4; ++k) deviation += valence(mesh.faces(f, k)) - regular(mesh.faces(f, k));
    bool irregular = false;
    for (int k = 0; k < 4; ++k)
      irregular = irregular || valence(mesh.faces(f, k)) != regular(mesh.faces(f, k));
    colours.row(f) = !irregular      ? Eigen::RowVector3f(0.62f, 0.76f, 0.90f)
                     : deviation > 0 ? Eigen::RowVector3f(0.95f, 0.62f, 0.55f)
                                     : Eigen::RowVector3f(0.98f, 0.85f, 0.45f);
  }
  return colours;
}

void run_fill(const FillOptions& options) {
  const std::vector<int> counts = parse_sides(options.sides);
  if (options.relax < 0) throw FillUsageError("--relax must be 0 or more sweeps");
  // Check counts (FillError, a std::invalid_argument) before any work on outputs.
  meshing::FillGeometryOptions geometry;
  geometry.relax_iterations = options.relax;
  if (counts.size() < 2) throw FillUsageError("--sides needs at least two edge counts, like 4,4");
  for (const int c : counts)
    if (c < 1)
      throw FillUsageError("every side needs at least 1 edge; got " + std::to_string(c) +
                           " in --sides " + options.sides);
  // The folders of --obj and --png can take files, before the fill (as every writing command).
  for (const std::string& file : {options.obj, options.png})
    if (!file.empty()) check_output_folder(std::filesystem::path(file).parent_path());
  const meshing::FilledPatch patch = meshing::fill_region(region_sides(counts), counts, geometry);
  const meshing::MeshCheck check = meshing::validate(patch.mesh);
  const auto& q = patch.quality;

  StagedOutputs outputs;
  if (!options.obj.empty()) outputs.stage(options.obj, meshing::to_obj(patch.mesh));
  if (!options.png.empty()) {
    const render::ImageSize size = render::parse_image_size(options.size);
    render::Renderer renderer;
    render::PatchStyle style;
    style.quad_colours = quad_colours(patch);
    const render::Image image =
        render::render_quad_patch(renderer, patch.mesh.vertices, patch.mesh.faces, size, style);
    outputs.stage(options.png, render::encode_png(image));
  }
  outputs.commit();

  nlohmann::json out = {{"sides", counts},
                        {"vertices", patch.mesh.vertices.rows()},
                        {"faces", patch.mesh.faces.rows()},
                        {"partition", patch.topology.partition},
                        {"distortion", q.distortion},
                        {"irregular_vertices", q.irregular_vertices},
                        {"valid", check.ok()},
                        {"problems", check.problems},
                        {"min_angle_deg", q.min_angle_deg},
                        {"max_angle_deg", q.max_angle_deg},
                        {"max_aspect_ratio", q.max_aspect_ratio},
                        {"scaled_jacobian_min", q.scaled_jacobian_min},
                        {"scaled_jacobian_mean", q.scaled_jacobian_mean},
                        {"inverted_quads", q.inverted_quads}};
  if (options.json) {
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::string sides;
  for (size_t i = 0; i < counts.size(); ++i) sides += (i ? "," : "") + std::to_string(counts[i]);
  std::cout << fmt::format(
      "sides               {}\nvertices            {}\nfaces               {}\n"
      "partition           {}\ndistortion          {}\nirregular_vertices  {}\n"
      "valid               {}\nmin_angle_deg       {:.2f}\nmax_angle_deg       {:.2f}\n"
      "max_aspect_ratio    {:.3f}\nscaled_jacobian_min {:.4f}\nscaled_jacobian_mean {:.4f}\n"
      "inverted_quads      {}\n",
      sides, patch.mesh.vertices.rows(), patch.mesh.faces.rows(), patch.topology.partition,
      q.distortion, q.irregular_vertices, check.ok() ? "yes" : "no", q.min_angle_deg,
      q.max_angle_deg, q.max_aspect_ratio, q.scaled_jacobian_min, q.scaled_jacobian_mean,
      q.inverted_quads);
  for (const auto& path : outputs.paths())
    std::cout << "wrote               " << path.string() << "\n";
}

}  // namespace

void add_fill_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<FillOptions>();
  CLI::App* cmd = app.add_subcommand(
      "fill", "Fill an n-sided region with a minimal-distortion quad mesh and report its quality");
  cmd->add_option("--sides", options->sides,
                  "Edge count of each side, counter-clockwise, e.g. 5,6,3,6,4 (even total)")
      ->required();
  cmd->add_flag("--json", options->json, "Print one JSON object instead of text");
  cmd->add_option("--obj", options->obj, "Write the filled patch as a Wavefront OBJ file");
  cmd->add_option("--png", options->png, "Render the patch flat with its quad edges to a PNG");
  cmd->add_option("--size", options->size, "PNG size WxH (default 800x800)");
  cmd->add_option("--relax", options->relax, "Relaxation sweeps after Coons interpolation");
  cmd->callback([options] { run_fill(*options); });
}

}  // namespace sd::app
