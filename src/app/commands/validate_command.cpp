// `sketchdrape validate SKETCH`: checks a sketch file the way `mesh` and `run` would use it —
// fields, body, strokes on the body, curve network, panels, edge counts, the quad fill, the
// fabric and the simulation settings — and writes nothing.

#include <fmt/format.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <mutex>

#include "garment/sketch_error.hpp"
#include "garment/unused_curves.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/cloth_scene.hpp"
#include "src/app/pipeline/pattern_export.hpp"
#include "src/app/pipeline/quality_warnings.hpp"
#include "src/app/pipeline/sketch_checks.hpp"

namespace sd::app {
namespace {

// Counts the warnings logged while it is attached to the default logger: the summary line's
// count is then the number of warning lines above it, whichever stage logged them (the body's
// repairs, the fabric's unusual constants, the pattern's stretch, the quality gate).
class WarningCounter final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  int count() {
    const std::lock_guard lock(mutex_);
    return count_;
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& message) override {
    if (message.level == spdlog::level::warn) ++count_;
  }
  void flush_() override {}

 private:
  int count_ = 0;
};

// Attaches a WarningCounter to the default logger for its lifetime.
class CountedWarnings {
 public:
  CountedWarnings() : counter_(std::make_shared<WarningCounter>()) {
    spdlog::default_logger()->sinks().push_back(counter_);
  }
  ~CountedWarnings() {
    auto& sinks = spdlog::default_logger()->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), counter_), sinks.end());
  }
  CountedWarnings(const CountedWarnings&) = delete;
  CountedWarnings& operator=(const CountedWarnings&) = delete;
  int count() const { return counter_->count(); }

 private:
  std::shared_ptr<WarningCounter> counter_;
};

struct ValidateOptions {
  std::string sketch;
  bool strict = false;
};

void run_validate(const ValidateOptions& options) {
  const CountedWarnings logged;
  const scene::Sketch sketch = scene::load_sketch(options.sketch);
  check_sketch(sketch);
  // What `run` would refuse for its size, refused here too (a sheet before it is built).
  const ClothScene scene = build_cloth_scene_within_limits(sketch);
  // The pattern `mesh` and `run` write when the file asks for one (output.pattern), laid out
  // here too: a fabric too narrow for a piece is refused by validate, not after a drape.
  if (scene.garment && sketch.output.pattern)
    (void)build_pattern_sheet(sketch, *scene.garment, *sketch.output.pattern,
                              scene.flat_pattern ? &*scene.flat_pattern : nullptr,
                              scene.flattening_ms, scene.body ? &*scene.body : nullptr);
  std::string what;
  if (scene.garment) {
    int distortion = 0;
    for (const auto& p : scene.garment->panels) distortion += p.distortion;
    what = fmt::format("{} curves, {} panels, {} quads, distortion {}", sketch.curves.size(),
                       scene.garment->panels.size(), scene.garment->mesh.face_count(), distortion);
  } else if (scene.imported) {
    // The file's own counts first (trial 41, P10: the √3 4-8 mesh's were given as the file's).
    const ClothScene::ImportedCounts& file = *scene.imported;
    what = fmt::format(
        "garment mesh: {} vertices, {} triangles{}; draped as a 4-8 mesh of {} vertices and {} "
        "triangles",
        file.vertices, file.triangles,
        file.faces != file.triangles ? fmt::format(" (its {} faces split)", file.faces) : "",
        scene.input.rest_positions.rows(), scene.input.triangles.rows());
  } else {
    // The fabric is named once, after this ("sheet: 95 vertices, ..., fabric viscose crepe").
    what = fmt::format("sheet: {} vertices, {} triangles", scene.input.rest_positions.rows(),
                       scene.input.triangles.rows());
  }
  std::vector<garment::QualityWarning> warnings;
  if (scene.garment && scene.body) warnings = quality_warnings(*scene.garment, sketch, *scene.body);
  // A fabric file by its own name ("medium linen"), not its path.
  const std::string fabric =
      scene.fabric_name.ends_with(".json") && scene.fabric.name != sim::FabricParameters{}.name
          ? scene.fabric.name
          : scene.fabric_name;
  // Every warning printed above is counted (--quiet prints none: the gate's are counted then);
  // the quality gate's share is named, since --strict acts on it.
  const int total = std::max(logged.count(), static_cast<int>(warnings.size()));
  std::string counted;
  if (total > 0)
    counted = warnings.empty() ? fmt::format("; {} warning(s)", total)
              : static_cast<size_t>(total) == warnings.size()
                  ? fmt::format("; {} mesh quality warning(s)", total)
                  : fmt::format("; {} warning(s), {} of them mesh quality warning(s)", total,
                                warnings.size());
  // The file's own text (its path, a fabric file's "name") as every message quotes it.
  std::cout << garment::printable(
                   fmt::format("{}: ok ({}, fabric {}){}", sketch.file, what, fabric, counted))
            << "\n";
  const size_t unused =
      scene.garment ? garment::unused_curve_warnings(sketch, *scene.garment).size() : 0;
  const size_t half_mirrored =
      scene.garment ? garment::half_mirrored_warnings(sketch, *scene.garment).size() : 0;
  if (const std::string failure = strict_failure(sketch.file, warnings, unused, half_mirrored);
      options.strict && !failure.empty())
    throw std::runtime_error(failure);
}

}  // namespace

void add_validate_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<ValidateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "Check a sketch file (fields, body, curves on the body, panels, edge counts); "
      "writes nothing");
  cmd->add_option("SKETCH", options->sketch, "Sketch file (format sketchdrape/1)")->required();
  cmd->add_flag("--strict", options->strict,
                "Exit with code 1 when the quality gate warns or a curve is in no panel");
  cmd->callback([options] { run_validate(*options); });
}

}  // namespace sd::app
