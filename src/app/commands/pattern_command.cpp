// `sketchdrape pattern SKETCH -o DIR`: the sketch's garment as a flat sewing pattern —
// pattern.svg, pattern.dxf and pattern.json (docs/pattern.md). No simulation. The files appear
// together or not at all.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/sketch_error.hpp"
#include "garment/sketch_inputs.hpp"
#include "garment/sketch_ranges.hpp"
#include "garment/unused_curves.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/pattern_export.hpp"

namespace sd::app {
namespace {

struct PatternOptions {
  std::string sketch;
  std::string out = ".";
  std::optional<double> fabric_width;    // m; default: the file's, else 1.5
  std::optional<double> seam_allowance;  // m; default: the file's, else 0.01
};

void run_pattern(const PatternOptions& options) {
  const scene::Sketch sketch = scene::load_sketch(options.sketch);
  if (sketch.sheet || sketch.garment_mesh)
    sketch.fail(sketch.sheet ? "/sheet" : "/garment_mesh",
                "a pattern is made from drawn panels; this file has none (a sheet or an imported "
                "garment mesh)");
  scene::PatternSpec spec = sketch.output.pattern.value_or(scene::PatternSpec{});
  if (options.fabric_width) spec.fabric_width = *options.fabric_width;
  if (options.seam_allowance) spec.seam_allowance = *options.seam_allowance;
  check_output_folder(options.out);
  const garment::Body body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(body.mesh);
  const garment::Garment g = garment::build_garment(sketch, surface);
  const std::vector<std::string> unused = garment::unused_curve_warnings(sketch, g);
  for (const std::string& warning : unused) spdlog::warn("{}", warning);
  const PatternSheet sheet = build_pattern_sheet(sketch, g, spec, nullptr, 0.0, &body);
  StagedOutputs outputs;
  outputs.keep(sketch.file);
  if (sketch.garment_mesh) outputs.keep(sketch.resolve(*sketch.garment_mesh));
  if (sketch.body.mesh != "builtin") outputs.keep(sketch.resolve(sketch.body.mesh));
  stage_pattern(sheet, options.out, outputs);
  outputs.commit();
  double worst = 0;
  for (const garment::PatternSeam& seam : sheet.pattern.seams)
    worst = std::max(worst, seam.mismatch());
  const garment::PatternLayout& layout = sheet.layout;
  // The pieces and the fabric as the SVG's footer and pattern.json say them (trial 40, P8: this
  // line counted every panel and its mirror copy, "16 pieces", where the sheet said 8 drawn, 12
  // to cut, and named no piece cut on the fold).
  std::cout << fmt::format(
      "{} → {}: {}, {:.0f} mm of {:.0f} mm wide fabric (every piece cut from one layer), "
      "efficiency {:.0f} %, seams within {:.2f} %, {} warning(s)\n",
      garment::printable(sketch.file), garment::printable(options.out),
      garment::printable(pieces_summary(piece_counts(sheet))), 1000 * layout.length_used,
      1000 * layout.fabric_width, 100 * layout.efficiency, 100 * worst,
      sheet.pattern.warnings.size() + unused.size());
}

}  // namespace

// A length option in metres checked as the file's lengths are, with the unit and the likely
// slip ("a fabric width of 60 m is outside 0.1 .. 10 m; ... if you typed centimetres, 60 cm
// is 0.6 m") instead of CLI11's "Value 60 not in range 0.100000 to 10.000000".
CLI::Validator length_in_range(double low, double high, std::string what,
                               garment::UsualRange usual) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = 0;
        try {
          size_t used = 0;
          value = std::stod(text, &used);
          if (used != text.size()) return fmt::format("'{}' is not a number of metres", text);
        } catch (const std::exception&) {
          return fmt::format("'{}' is not a number of metres", text);
        }
        if (value >= low && value <= high) return "";
        return garment::out_of_range_sentence(value, low, high, what, usual);
      },
      fmt::format("metres, {} .. {}", low, high));
}

void add_pattern_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<PatternOptions>();
  CLI::App* cmd = app.add_subcommand(
      "pattern",
      "Flatten a sketch file's panels into a sewing pattern (pattern.svg, pattern.dxf, "
      "pattern.json); no simulation");
  cmd->add_option("SKETCH", options->sketch, "Sketch file (format sketchdrape/1)")->required();
  cmd->add_option("-o,--out", options->out, "Output directory (created if needed)")
      ->check(non_empty_path());
  cmd->add_option("--fabric-width", options->fabric_width,
                  "Fabric width in metres (default: output.pattern.fabric_width, else 1.5)")
      ->check(length_in_range(0.1, 10.0, "a fabric width of", garment::kUsualFabricWidth));
  cmd->add_option("--seam-allowance", options->seam_allowance,
                  "Seam allowance in metres for pieces without their own (default: "
                  "output.pattern.seam_allowance, else 0.01)")
      ->check(length_in_range(0.0, 0.1, "a seam allowance of", garment::kUsualSeamAllowance));
  cmd->callback([options] { run_pattern(*options); });
}

}  // namespace sd::app
