#pragma once
// The sewing pattern of a garment as files: pattern.svg (true scale, mm; the pieces nested on the
// fabric, labelled, with sewing and cutting lines, grain lines, notches and a scale bar),
// pattern.dxf (AAMA/ASTM D6673 style: one block per piece, layers 1 boundary, 4 notches, 7 grain
// line, 14 sewing line, 15 annotation; mm) and pattern.json (2D polygons, seams as pairs of 2D
// polylines, distortion figures, fabric used). docs/pattern.md describes them.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/panel_flattening.hpp"
#include "garment/pattern_layout.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/pipeline/atomic_file.hpp"

namespace sd::app {

struct PatternSheet {
  std::string title;  // the sketch file's name
  garment::FlatPattern pattern;
  garment::PatternLayout layout;
  std::vector<std::string> fabrics;  // per panel
  double flatten_ms = 0, layout_ms = 0;
};

// Flattens and lays out the garment's panels with the file's pattern settings (`spec`, with each
// panel's own seam allowance). A panel that cannot be flattened becomes a SketchError at that
// panel's JSON path; stretch warnings are logged. `flattened`, when given, is the same garment
// already flattened with `spec`'s warning threshold (a drape from the flat pattern, which has
// logged its warnings): it is laid out as it is, neither flattened nor reported twice. With
// `body`, a panel that cannot be flattened is reported after the quality gate's warnings and
// with the cloth of it inside the body (flattening_failure in quality_warnings.hpp).
PatternSheet build_pattern_sheet(const scene::Sketch& sketch, const garment::Garment& garment,
                                 const scene::PatternSpec& spec,
                                 const garment::FlatPattern* flattened = nullptr,
                                 double flattened_ms = 0.0, const garment::Body* body = nullptr);

// The panels `pattern` cuts on the fold (ids, in pattern order), by build_pattern_sheet's own
// decision (fold_edges: a centre line the flattening held straight, one straight run on the
// grain, without an allowance of its own, both halves across the fabric) for the garment
// flattened as `pattern` flattens it (`pattern`, FlatteningOptions' defaults) with `spec`.
std::vector<std::string> panels_cut_on_fold(const scene::Sketch& sketch,
                                            const garment::Garment& garment,
                                            const scene::PatternSpec& spec,
                                            const garment::FlatPattern& pattern);

// The pieces as the `pattern` command's line, the SVG's footer and pattern.json
// ("pieces_summary") all say them: how many pieces are cut, how many are drawn when that
// differs, and the pieces cut on the fold by name and the mirror pairs by count. "12 pieces to
// cut, drawn as 8 (4 cut on the fold: 'cfront', 'cback', 'skirt_cf', 'skirt_cb'; 4 mirror pairs
// drawn once, cut 2)"; "2 pieces to cut (2 cut on the fold: 'front', 'back')"; "5 pieces to cut".
struct PieceCounts {
  int to_cut = 0;                    // every piece as often as it is cut; a piece on the fold once
  int drawn = 0;                     // on the sheet: a mirror pair once, a fold piece as its half
  std::vector<std::string> on_fold;  // the pieces cut on the fold, in pattern order
  int mirror_pairs = 0;
};
PieceCounts piece_counts(const PatternSheet& sheet);
std::string pieces_summary(const PieceCounts& counts);

std::string pattern_svg(const PatternSheet& sheet);
std::string pattern_dxf(const PatternSheet& sheet);
nlohmann::json pattern_json(const PatternSheet& sheet);

// A panel's ease as its file gives it: a number when it is the same both ways, else
// {"warp": a, "weft": b} (a gathered panel).
nlohmann::json ease_json(const garment::PanelEase& ease);

// The figures a run report holds: per piece distortion and size, worst seam mismatch, fabric
// length and efficiency.
nlohmann::json pattern_summary(const PatternSheet& sheet);

// Stages pattern.svg, pattern.dxf and pattern.json in `dir`.
void stage_pattern(const PatternSheet& sheet, const std::filesystem::path& dir,
                   StagedOutputs& outputs);

}  // namespace sd::app
