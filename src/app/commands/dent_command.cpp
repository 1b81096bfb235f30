// `sketchdrape dent MESH`: how deep a draped garment dents between supports (a skirt pulled in
// between the legs): the deepest distance of a horizontal slice from its convex hull, over
// slices from 10 % to 60 % of the mesh's height (meshing/slice_dent.hpp).

#include <fmt/format.h>

#include <iostream>

#include "garment/body.hpp"
#include "garment/sketch_error.hpp"
#include "meshing/slice_dent.hpp"
#include "src/app/commands/cli.hpp"

namespace sd::app {
namespace {

struct DentOptions {
  std::string mesh;
  double from = 0.1;
  double to = 0.6;
};

void run_dent(const DentOptions& options) {
  if (!(options.from >= 0 && options.from < options.to && options.to <= 1))
    throw std::invalid_argument(fmt::format(
        "--from {} and --to {} must be fractions of the height with 0 <= from < to <= 1",
        options.from, options.to));
  // Read as it is: metres, Y up (the loader only moves it, which does not change the measure).
  garment::BodyOptions read_as_is;
  read_as_is.scale = 1.0;
  read_as_is.up = garment::AxisDirection::parse("y");
  const garment::Body mesh = garment::load_body(options.mesh, read_as_is);
  const meshing::SliceDent dent = meshing::slice_dent(mesh.mesh, options.from, options.to);
  std::cout << fmt::format(
      "{}: slice dent {:.4f} m at {:.0f} % of the height ({} slices from {:.0f} % to {:.0f} %)\n",
      garment::printable(options.mesh), dent.depth,
      100 * (dent.height - mesh.mesh.vertices.col(1).minCoeff()) /
          std::max(1e-12,
                   mesh.mesh.vertices.col(1).maxCoeff() - mesh.mesh.vertices.col(1).minCoeff()),
      dent.slices, 100 * options.from, 100 * options.to);
}

}  // namespace

void add_dent_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<DentOptions>();
  CLI::App* cmd = app.add_subcommand(
      "dent",
      "Measure how deep a draped garment's horizontal slices dent inward from their "
      "convex hull (a skirt pulled between the legs)");
  cmd->add_option("MESH", options->mesh, "Draped mesh (drape.obj; metres, Y up)")->required();
  cmd->add_option("--from", options->from, "Lowest slice, fraction of the height (0.1)");
  cmd->add_option("--to", options->to, "Highest slice, fraction of the height (0.6)");
  cmd->callback([options] { run_dent(*options); });
}

}  // namespace sd::app
