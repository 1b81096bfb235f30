#include "src/app/pipeline/pattern_export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>

#include "sim/fabric.hpp"
#include "src/app/pipeline/markup_escape.hpp"
#include "src/app/pipeline/pattern_label.hpp"
#include "src/app/pipeline/quality_warnings.hpp"

namespace sd::app {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

constexpr double kMm = 1000.0;  // metres → millimetres

// The sketch's panel a garment panel comes from ("front.mirror" → "front").
const garment::PanelSpec* panel_spec(const scene::Sketch& sketch, const std::string& id) {
  if (const garment::PanelSpec* p = sketch.find_panel(id)) return p;
  const std::string suffix = ".mirror";
  if (id.ends_with(suffix)) return sketch.find_panel(id.substr(0, id.size() - suffix.size()));
  return nullptr;
}

// Piece point (m, piece frame) → fabric point (mm, x across, y along the bolt).
Eigen::Vector2d on_fabric(const garment::PatternPiece& piece, const Eigen::Vector2d& p) {
  return kMm * (p + piece.placement);
}

// A notch: a snip 5 mm deep into the seam allowance from the cutting line, on the sewing line's
// normal (the whole allowance when it is narrower).
std::pair<Eigen::Vector2d, Eigen::Vector2d> notch_segment(const garment::PatternNotch& n) {
  const double a = n.allowance;
  const double depth = std::min(a, 0.005);
  if (a <= 0) return {n.point - 0.004 * n.normal, n.point};  // no allowance: a snip inwards
  return {n.point + a * n.normal, n.point + (a - depth) * n.normal};
}

// The piece's seam allowance in mm for a label: "10", or "10-30" when its seams differ. A fold
// has none and is no seam: it is left out.
std::string allowance_mm(const garment::PatternPiece& piece) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const garment::AllowanceRun& run : piece.allowances) {
    if (piece.on_fold && run.allowance == 0) continue;
    lo = std::min(lo, run.allowance);
    hi = std::max(hi, run.allowance);
  }
  if (!(lo <= hi)) lo = hi = piece.allowance;
  return hi - lo < 5e-4 ? fmt::format("{:.0f}", kMm * lo)
                        : fmt::format("{:.0f}-{:.0f}", kMm * lo, kMm * hi);
}

// The curve's own seam allowance of every outline edge of a piece (m; −1: the piece's), from the
// curve each edge lies on (Garment::edge_curve; a mirror copy's curve takes its original's).
std::vector<double> edge_allowances(const scene::Sketch& sketch, const garment::Garment& garment,
                                    const garment::FlatPanel& flat) {
  std::vector<double> out(flat.boundary.size(), -1.0);
  bool any = false;
  for (size_t k = 0; k < flat.boundary.size(); ++k) {
    const int a = flat.vertices[static_cast<size_t>(flat.boundary[k])];
    const int b = flat.vertices[static_cast<size_t>(flat.boundary[(k + 1) % flat.boundary.size()])];
    const auto found = garment.edge_curve.find(std::minmax(a, b));
    if (found == garment.edge_curve.end()) continue;  // takes its neighbour's (below)
    std::string id = found->second;
    if (id.ends_with(".mirror")) id.resize(id.size() - 7);
    for (const garment::CurveSpec& curve : sketch.curves)
      if (curve.id == id && curve.seam_allowance) {
        out[k] = *curve.seam_allowance;
        any = true;
      }
  }
  if (!any) out.clear();
  // An edge on no curve (the diagonal a quad over the mirror plane is cut along,
  // panel_flattening.cpp) continues the curve before it.
  for (size_t k = 0; k < out.size(); ++k)
    if (const int a = flat.vertices[static_cast<size_t>(flat.boundary[k])],
        b = flat.vertices[static_cast<size_t>(flat.boundary[(k + 1) % out.size()])];
        !garment.edge_curve.contains(std::minmax(a, b)) && k > 0)
      out[k] = out[k - 1];
  return out;
}

// The outline points of a piece where its outline passes from one sketch curve to the next
// (a mirror copy's curve counts as its original's): corners its smooth sewing line keeps.
std::vector<bool> curve_corners(const garment::Garment& garment, const garment::FlatPanel& flat) {
  const size_t n = flat.boundary.size();
  std::vector<std::string> curve(n);
  for (size_t k = 0; k < n; ++k) {
    const int a = flat.vertices[static_cast<size_t>(flat.boundary[k])];
    const int b = flat.vertices[static_cast<size_t>(flat.boundary[(k + 1) % n])];
    const auto found = garment.edge_curve.find(std::minmax(a, b));
    if (found != garment.edge_curve.end()) curve[k] = found->second;
  }
  // An edge on no curve (the diagonal a quad over the mirror plane is cut along,
  // panel_flattening.cpp) continues the curve before it: no corner at its ends.
  for (size_t k = 0; k < 2 * n; ++k)
    if (curve[k % n].empty()) curve[k % n] = curve[(k + n - 1) % n];
  std::vector<bool> out(n, false);
  for (size_t k = 0; k < n; ++k) out[k] = curve[k] != curve[(k + n - 1) % n];
  return out;
}

// m: how far a centre-line edge may bow from its chord and still be laid on the fold. Cut on
// the fold, the piece's centre follows the chord instead: the whole piece, both halves, is at
// most twice this wider or narrower there (4 mm of girth), well inside a garment's ease. The
// flattening does not hold centre lines straight: measured bows are 0.3-1.6 mm on yokes, gores
// and collars, 2-37 mm on bodice and skirt fronts and backs, 29-61 mm on crotch curves
// (docs/pattern.md), so only the first are folded.
constexpr double kFoldStraightness = 2e-3;

// The outline edges of panel `flat` (not a mirror copy) that lie on the garment's mirror plane
// x = 0, when its mirror copy is in the pattern and those edges make one straight run (within
// kFoldStraightness of its chord, in 2D) along the grain line or across it (within
// `off_grain_deg`: the fold is a thread of the folded fabric) and opened out the piece fits
// across the fabric: the piece is cut on the fold there, and stands for its copy too. Empty
// otherwise.
std::vector<bool> fold_edges(const garment::Garment& garment, const garment::FlatPattern& pattern,
                             const garment::FlatPanel& flat, const std::vector<double>& own,
                             double opened_width_limit, double off_grain_deg) {
  if (flat.id.ends_with(".mirror")) return {};
  // A centre line that the warp beside it crosses somewhere (a crotch curve) is no thread,
  // however straight it lies in the piece (FlatteningOptions::fold_across_warp_deg).
  if (flat.centre_across_warp_deg > garment::FlatteningOptions{}.fold_across_warp_deg) return {};
  const bool has_copy = std::any_of(pattern.panels.begin(), pattern.panels.end(),
                                    [&](const auto& p) { return p.id == flat.id + ".mirror"; });
  if (!has_copy) return {};
  const size_t n = flat.boundary.size();
  const auto on_plane = [&](size_t k) {
    const int v = flat.vertices[static_cast<size_t>(flat.boundary[k % n])];
    return std::abs(garment.mesh.vertices(v, 0)) <= 1e-6;
  };
  std::vector<bool> fold(n, false);
  size_t runs = 0, first = 0;
  for (size_t k = 0; k < n; ++k) {
    fold[k] = on_plane(k) && on_plane(k + 1);
    const bool starts = fold[k] && !(on_plane(k + n - 1) && on_plane(k));
    if (starts) first = k;
    runs += starts;
  }
  if (runs != 1) return {};
  // A centre curve with its own seam allowance is sewn (a centre-back zip), not folded.
  for (size_t k = 0; k < n && !own.empty(); ++k)
    if (fold[k] && own[k] >= 0) return {};
  size_t last = first;
  while (fold[(last + 1) % n] && (last + 1) % n != first) last = (last + 1) % n;
  const Eigen::Vector2d a = flat.uv.row(flat.boundary[first]).transpose();
  const Eigen::Vector2d b = flat.uv.row(flat.boundary[(last + 1) % n]).transpose();
  const Eigen::Vector2d along = (b - a).normalized();
  for (size_t k = first; k != (last + 1) % n; k = (k + 1) % n) {
    const Eigen::Vector2d q = flat.uv.row(flat.boundary[(k + 1) % n]).transpose() - a;
    if (std::abs(along.x() * q.y() - along.y() * q.x()) > kFoldStraightness) return {};
  }
  // The piece's grain line is +y: the fold along it or across it, not on the bias.
  const double off = std::acos(std::min(1.0, std::abs(along.y()))) * 180.0 / std::numbers::pi;
  if (off > off_grain_deg && 90.0 - off > off_grain_deg) return {};
  // Opened out (the piece and its reflection across the fold), both halves must fit across the
  // fabric (the layout lays it out so).
  double lo = 0, hi = 0;
  for (Eigen::Index v = 0; v < flat.uv.rows(); ++v) {
    const Eigen::Vector2d p = flat.uv.row(v).transpose() - a;
    const Eigen::Vector2d mirrored = 2 * p.dot(along) * along - p;
    lo = std::min({lo, p.x(), mirrored.x()});
    hi = std::max({hi, p.x(), mirrored.x()});
  }
  if (hi - lo > opened_width_limit) return {};
  return fold;
}

std::string piece_name(const PatternSheet& sheet, const garment::PatternPiece& piece) {
  return sheet.pattern.panels[static_cast<size_t>(piece.panel)].id;
}

// The piece's mirror image in the pattern ("front" ↔ "front.mirror"), empty when it has none.
std::string mirror_partner(const PatternSheet& sheet, const std::string& id) {
  const std::string suffix = ".mirror";
  const std::string other =
      id.ends_with(suffix) ? id.substr(0, id.size() - suffix.size()) : id + suffix;
  for (const garment::FlatPanel& panel : sheet.pattern.panels)
    if (panel.id == other) return other;
  return {};
}

// The piece label's ease: "ease 1.05", or for a gathered piece the factor each way.
std::string ease_label(const garment::PanelEase& ease) {
  if (ease.isotropic()) return fmt::format("ease {:g}", ease.warp);
  return fmt::format("gathered: ease {:g} along, {:g} across the grain", ease.warp, ease.weft);
}

// How often a piece is cut, naming its mirror image when the garment has one: "cut 2 (mirror
// pair) · front and front.mirror" for a piece drawn once for both (their pieces each other's
// reflection: cut twice, the second turned over); else "cut 1", "cut 1 · pair with
// front.mirror", "cut 1 · mirror of front" for a pair that differs and is drawn twice.
std::string cut_note(const PatternSheet& sheet, const garment::PatternPiece& piece) {
  const std::string id = piece_name(sheet, piece);
  if (piece.on_fold) return "CUT 1 ON FOLD";
  const std::string partner = mirror_partner(sheet, id);
  if (piece.quantity == 2) return fmt::format("cut 2 (mirror pair) · {} and {}", id, partner);
  if (partner.empty()) return "cut 1";
  return (id.ends_with(".mirror") ? "cut 1 · mirror of " : "cut 1 · pair with ") + partner;
}

// ------------------------------------------------------------------------------------------------
// SVG

std::string svg_path(const garment::PatternPiece& piece, const Eigen::MatrixX2d& polygon,
                     double height) {
  std::string d;
  for (Eigen::Index i = 0; i < polygon.rows(); ++i) {
    const Eigen::Vector2d p = on_fabric(piece, polygon.row(i).transpose());
    d += fmt::format("{}{:.2f},{:.2f} ", i == 0 ? "M" : "L", p.x(), height - p.y());
  }
  return d + "Z";
}

// The smooth sewing line as cubic Béziers (mm, SVG frame).
std::string svg_curve(const garment::PatternPiece& piece, double height) {
  const auto at = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d q = on_fabric(piece, p);
    return fmt::format("{:.2f},{:.2f}", q.x(), height - q.y());
  };
  const Eigen::Index n = piece.sewing.rows();
  std::string d = "M" + at(piece.sewing.row(0).transpose());
  for (Eigen::Index k = 0; k < n; ++k) {
    const garment::BezierSpan& span = piece.curve.spans[static_cast<size_t>(k)];
    d += " C" + at(span.b1) + " " + at(span.b2) + " " +
         at(piece.sewing.row((k + 1) % n).transpose());
  }
  return d + " Z";
}

// "Place on fold": the fold line (dash-dot) and the pattern maker's bracket beside it, a line
// parallel to the fold 12 mm inside the piece with legs ending in arrows on the fold at a fifth
// and four fifths of its length, labelled "CUT 1 ON FOLD" (SVG, mm).
std::string svg_fold(const garment::PatternPiece& piece, double height) {
  const auto sheet = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d q = on_fabric(piece, p);
    return Eigen::Vector2d(q.x(), height - q.y());
  };
  const Eigen::Vector2d a = sheet(piece.fold_start), b = sheet(piece.fold_end);
  const Eigen::Vector2d along = (b - a).normalized();
  // Inside: the piece's outline runs counter-clockwise in the piece frame, clockwise on the
  // sheet (y flipped), so the inside is right of a → b on the sheet.
  const Eigen::Vector2d in(-along.y(), along.x());
  const Eigen::Vector2d inside = -in;
  const Eigen::Vector2d p = a + 0.2 * (b - a), q = a + 0.8 * (b - a);
  const double depth = 12, head = 3;
  const Eigen::Vector2d p1 = p + depth * inside, q1 = q + depth * inside;
  const auto arrow = [&](const Eigen::Vector2d& tip) {
    const Eigen::Vector2d l = tip + head * inside + 0.5 * head * along;
    const Eigen::Vector2d r = tip + head * inside - 0.5 * head * along;
    return fmt::format(" M{:.2f},{:.2f} L{:.2f},{:.2f} L{:.2f},{:.2f}", l.x(), l.y(), tip.x(),
                       tip.y(), r.x(), r.y());
  };
  // The fold runs along the cutting line: white under it, so that its dashes show.
  std::string out;
  for (const char* kind : {"fold-gap", "fold"})
    out += fmt::format(
        "<line class=\"{}\" x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\"/>\n", kind,
        a.x(), a.y(), b.x(), b.y());
  out += fmt::format(
      "<path class=\"fold-mark\" d=\"M{:.2f},{:.2f} L{:.2f},{:.2f} L{:.2f},{:.2f} "
      "L{:.2f},{:.2f}{}{}\"/>\n",
      p.x(), p.y(), p1.x(), p1.y(), q1.x(), q1.y(), q.x(), q.y(), arrow(p), arrow(q));
  const Eigen::Vector2d mid = 0.5 * (p1 + q1) + 2.0 * inside;
  double angle = std::atan2(along.y(), along.x()) * 180 / M_PI;
  if (angle > 90) angle -= 180;
  if (angle < -90) angle += 180;
  // The text 2 mm inside the bracket, turned to read along the fold.
  out += fmt::format(
      "<text class=\"fold-label\" x=\"0\" y=\"0\" font-size=\"4\" text-anchor=\"middle\" "
      "dominant-baseline=\"hanging\" transform=\"translate({:.2f} {:.2f}) rotate({:.1f})\">CUT 1 "
      "ON FOLD</text>\n",
      mid.x(), mid.y(), angle);
  return out;
}

// The fabric as a pattern piece names it: a fabric file by its "name" ("medium linen", not
// "../fabrics/linen.json"), else by the file's stem; a preset or an inline fabric by its name.
std::string fabric_label(const scene::Sketch& sketch, const std::string& fabric) {
  if (!fabric.ends_with(".json") || (fabric == sketch.fabric && !sketch.fabric_inline.empty()))
    return fabric;
  try {
    const sim::FabricParameters parameters = sim::load_fabric_file(sketch.resolve(fabric).string());
    if (parameters.name != sim::FabricParameters{}.name) return parameters.name;
  } catch (const sim::InvalidFabricError&) {
    // `run` and `validate` report a bad fabric file; the pattern is labelled by its stem.
  }
  return std::filesystem::path(fabric).stem().string();
}

// The layout's settings for the garment flattened as `pattern` flattens it: `spec`'s allowance
// and fabric width, each panel's own allowance, its ease and corners, and where each piece is cut
// on the fold (fold_edges). One decision for build_pattern_sheet and panels_cut_on_fold.
garment::PatternLayoutOptions layout_options(const scene::Sketch& sketch,
                                             const garment::Garment& garment,
                                             const scene::PatternSpec& spec,
                                             const garment::FlatPattern& pattern) {
  garment::PatternLayoutOptions layout;
  layout.fabric_width = spec.fabric_width;
  layout.seam_allowance = spec.seam_allowance;
  for (const garment::FlatPanel& flat : pattern.panels) {
    const garment::GarmentPanel& panel = garment.panels[static_cast<size_t>(flat.panel)];
    const garment::PanelSpec* ps = panel_spec(sketch, panel.id);
    layout.panel_allowance.push_back(ps && ps->seam_allowance ? *ps->seam_allowance : -1.0);
    layout.edge_allowance.push_back(edge_allowances(sketch, garment, flat));
    layout.panel_ease.push_back(panel.ease);
    layout.corners.push_back(curve_corners(garment, flat));
    // The widest the half of a fold piece may be, flattened (m): both halves with their
    // widest allowance, the gaps at the selvedges and 2 mm columns' rounding each side.
    double widest_allowance =
        layout.panel_allowance.back() >= 0 ? layout.panel_allowance.back() : spec.seam_allowance;
    for (const double a : layout.edge_allowance.back())
      widest_allowance = std::max(widest_allowance, a);
    const double opened_limit =
        (spec.fabric_width - 2 * layout.gap - 0.008) / panel.ease.weft - 2 * widest_allowance;
    layout.fold_edge.push_back(fold_edges(garment, pattern, flat, layout.edge_allowance.back(),
                                          opened_limit,
                                          garment::FlatteningOptions{}.fold_off_grain_deg));
  }
  // A fold piece's mirror copy is its other half: not cut on its own.
  layout.folded_into.assign(pattern.panels.size(), -1);
  for (size_t p = 0; p < pattern.panels.size(); ++p)
    if (!layout.fold_edge[p].empty())
      for (size_t q = 0; q < pattern.panels.size(); ++q)
        if (pattern.panels[q].id == pattern.panels[p].id + ".mirror")
          layout.folded_into[q] = static_cast<int>(p);
  return layout;
}

}  // namespace

PatternSheet build_pattern_sheet(const scene::Sketch& sketch, const garment::Garment& garment,
                                 const scene::PatternSpec& spec,
                                 const garment::FlatPattern* flattened, double flattened_ms,
                                 const garment::Body* body) {
  PatternSheet sheet;
  sheet.title = std::filesystem::path(sketch.file).filename().string();
  garment::FlatteningOptions flattening;
  flattening.warn_stretch = spec.max_stretch;
  const auto start = Clock::now();
  try {
    sheet.pattern = flattened ? *flattened : garment::flatten_garment(garment, flattening);
    sheet.flatten_ms = flattened ? flattened_ms : ms_since(start);
    const garment::PatternLayoutOptions layout =
        layout_options(sketch, garment, spec, sheet.pattern);
    for (const garment::FlatPanel& flat : sheet.pattern.panels)
      sheet.fabrics.push_back(
          fabric_label(sketch, garment.panels[static_cast<size_t>(flat.panel)].fabric));
    const auto layout_start = Clock::now();
    sheet.layout = garment::lay_out_pattern(sheet.pattern, layout);
    sheet.layout_ms = ms_since(layout_start);
  } catch (const garment::PatternError& e) {
    const garment::PanelSpec* ps = panel_spec(sketch, e.panel());
    sketch.fail(ps ? ps->json_path : "/panels",
                body ? flattening_failure(garment, sketch, *body, e) : e.what());
  }
  if (!flattened)
    for (const std::string& warning : sheet.pattern.warnings) spdlog::warn("{}", warning);
  return sheet;
}

std::vector<std::string> panels_cut_on_fold(const scene::Sketch& sketch,
                                            const garment::Garment& garment,
                                            const scene::PatternSpec& spec,
                                            const garment::FlatPattern& pattern) {
  const garment::PatternLayoutOptions layout = layout_options(sketch, garment, spec, pattern);
  std::vector<std::string> folded;
  for (size_t p = 0; p < pattern.panels.size(); ++p)
    if (!layout.fold_edge[p].empty()) folded.push_back(pattern.panels[p].id);
  return folded;
}

PieceCounts piece_counts(const PatternSheet& sheet) {
  PieceCounts counts;
  for (const garment::PatternPiece& piece : sheet.layout.pieces) {
    if (piece.folded_into < 0) ++counts.to_cut;
    if (piece.quantity > 0) ++counts.drawn;
    if (piece.on_fold) counts.on_fold.push_back(piece_name(sheet, piece));
  }
  counts.mirror_pairs = sheet.layout.pairs;
  return counts;
}

std::string pieces_summary(const PieceCounts& counts) {
  std::string text = fmt::format("{} piece{} to cut", counts.to_cut, counts.to_cut == 1 ? "" : "s");
  if (counts.drawn != counts.to_cut) text += fmt::format(", drawn as {}", counts.drawn);
  std::vector<std::string> how;
  if (!counts.on_fold.empty()) {
    std::vector<std::string> quoted;
    for (const std::string& id : counts.on_fold) quoted.push_back("'" + id + "'");
    how.push_back(
        fmt::format("{} cut on the fold: {}", counts.on_fold.size(), fmt::join(quoted, ", ")));
  }
  if (counts.mirror_pairs > 0)
    how.push_back(fmt::format("{} mirror pair{} drawn once, cut 2", counts.mirror_pairs,
                              counts.mirror_pairs == 1 ? "" : "s"));
  if (!how.empty()) text += fmt::format(" ({})", fmt::join(how, "; "));
  return text;
}

std::string pattern_svg(const PatternSheet& sheet) {
  const garment::PatternLayout& layout = sheet.layout;
  const double width = kMm * layout.fabric_width;
  const double length = kMm * layout.sheet_length;
  const double footer = 40;  // mm below the fabric: title and scale bar
  std::string svg = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.1f}mm\" height=\"{1:.1f}mm\" "
      "viewBox=\"0 0 {0:.1f} {1:.1f}\" font-family=\"sans-serif\">\n"
      "<title>{2} sewing pattern</title>\n"
      "<style>.fabric{{fill:#f4efe4;stroke:#8a8170;stroke-width:0.6}}"
      ".cut{{fill:#ffffff;stroke:#000;stroke-width:0.5}}"
      ".sew{{fill:none;stroke:#c0392b;stroke-width:0.35;stroke-dasharray:3 1.5}}"
      ".grain{{stroke:#1f4e9c;stroke-width:0.5;fill:none}}.notch{{stroke:#000;stroke-width:0.6}}"
      ".label{{fill:#222}}.note{{fill:#444}}"
      ".fold{{stroke:#000;stroke-width:0.5;stroke-dasharray:8 2 1 2}}"
      ".fold-gap{{stroke:#fff;stroke-width:0.9}}"
      ".fold-mark{{stroke:#000;stroke-width:0.4;fill:none}}.fold-label{{fill:#000}}</style>\n"
      "<rect class=\"fabric\" x=\"0\" y=\"0\" width=\"{0:.1f}\" height=\"{3:.1f}\"/>\n",
      width, length + footer, markup_escape(sheet.title), length);
  for (const garment::PatternPiece& piece : layout.pieces) {
    // Drawn as its mirror pair's piece, or the other half of a piece cut on the fold.
    if (piece.quantity == 0) continue;
    const garment::FlatPanel& flat = sheet.pattern.panels[static_cast<size_t>(piece.panel)];
    const std::string name = piece_name(sheet, piece);
    const std::string fabric = sheet.fabrics[static_cast<size_t>(piece.panel)];
    svg += fmt::format(
        "<g class=\"piece\" id=\"piece-{0}\" data-panel=\"{0}\" data-cut=\"{1}\"{2}{3}>\n",
        markup_escape(name), piece.quantity,
        piece.quantity == 2
            ? fmt::format(" data-mirror=\"{}\"", markup_escape(mirror_partner(sheet, name)))
            : std::string(),
        piece.on_fold ? " data-fold=\"1\"" : "");
    svg += fmt::format("<path class=\"cut\" d=\"{}\"/>\n", svg_path(piece, piece.cutting, length));
    svg += fmt::format("<path class=\"sew\" d=\"{}\"/>\n", svg_curve(piece, length));
    if (piece.on_fold) svg += svg_fold(piece, length);
    const Eigen::Vector2d g0 = on_fabric(piece, piece.grain_start);
    const Eigen::Vector2d g1 = on_fabric(piece, piece.grain_end);
    const double head = std::min(4.0, 0.2 * (g1 - g0).norm());
    svg += fmt::format(
        "<path class=\"grain\" d=\"M{0:.2f},{1:.2f} L{0:.2f},{2:.2f} M{3:.2f},{4:.2f} "
        "L{0:.2f},{1:.2f} "
        "L{5:.2f},{4:.2f} M{3:.2f},{6:.2f} L{0:.2f},{2:.2f} L{5:.2f},{6:.2f}\"/>\n",
        g0.x(), length - g0.y(), length - g1.y(), g0.x() - 0.5 * head, length - g0.y() - head,
        g0.x() + 0.5 * head, length - g1.y() + head);
    for (const garment::PatternNotch& n : piece.notches) {
      const auto [a, b] = notch_segment(n);
      const Eigen::Vector2d pa = on_fabric(piece, a), pb = on_fabric(piece, b);
      svg += fmt::format(
          "<line class=\"notch{}\" x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\"/>\n",
          n.balance ? " balance" : "", pa.x(), length - pa.y(), pb.x(), length - pb.y());
    }
    // The label where it fits inside the piece (pattern_label.hpp).
    LabelText text;
    text.title = name;
    text.lines = {
        fmt::format("{:.0f} × {:.0f} mm · {}",
                    kMm * (piece.sewing.col(0).maxCoeff() - piece.sewing.col(0).minCoeff()),
                    kMm * (piece.sewing.col(1).maxCoeff() - piece.sewing.col(1).minCoeff()),
                    fabric),
        fmt::format("{} · {} · stretch {:.1f} % (95th pct)", cut_note(sheet, piece),
                    ease_label(piece.ease), 100 * flat.distortion.length_p95)};
    Eigen::MatrixX2d outline(piece.sewing.rows(), 2);
    for (Eigen::Index i = 0; i < piece.sewing.rows(); ++i) {
      const Eigen::Vector2d p = on_fabric(piece, piece.sewing.row(i).transpose());
      outline.row(i) << p.x(), length - p.y();
    }
    const LabelPlacement at =
        place_label(outline, {g0.x(), length - g0.y()}, {g1.x(), length - g1.y()}, text);
    svg += fmt::format("<g class=\"label\" transform=\"translate({:.1f} {:.1f}){}\"{}>\n",
                       at.anchor.x(), at.anchor.y(),
                       at.turn_deg != 0 ? fmt::format(" rotate({:g})", -at.turn_deg) : "",
                       at.centred ? " text-anchor=\"middle\"" : "");
    svg +=
        fmt::format("<text x=\"0\" y=\"0\" font-size=\"{:.1f}\" font-weight=\"bold\">{}</text>\n",
                    at.size, markup_escape(text.title));
    for (size_t k = 0; k < text.lines.size(); ++k)
      svg += fmt::format("<text x=\"0\" y=\"{:.1f}\" font-size=\"{:.1f}\">{}</text>\n",
                         at.size * (1 + 0.9 * double(k)), 0.75 * at.size,
                         markup_escape(text.lines[k]));
    svg += "</g>\n";
    svg += "</g>\n";
  }
  // Scale bar: 100 mm in 10 mm steps, and the sheet's figures.
  const double y = length + 12;
  svg += "<g class=\"scale-bar\">\n";
  svg += fmt::format(
      "<rect x=\"10\" y=\"{:.1f}\" width=\"100\" height=\"3\" fill=\"none\" stroke=\"#000\" "
      "stroke-width=\"0.4\"/>\n",
      y);
  for (int k = 0; k < 10; k += 2)
    svg += fmt::format("<rect x=\"{}\" y=\"{:.1f}\" width=\"10\" height=\"3\" fill=\"#000\"/>\n",
                       10 + 10 * k, y);
  svg += fmt::format(
      "<text x=\"10\" y=\"{:.1f}\" font-size=\"4\">0</text><text x=\"100\" y=\"{:.1f}\" "
      "font-size=\"4\">100 mm</text>\n</g>\n",
      y + 8, y + 8);
  // The fabric a cutter needs (every piece from one layer) is the figure everywhere (the
  // `pattern` line, pattern.json's fabric_length_mm and efficiency); the sheet's own length is
  // the drawing's, where a mirror pair is drawn once and a fold piece as its half (trial 40, P8:
  // the footer said "799 mm used · efficiency 45 %" where the line said 1345 mm and 53 %).
  svg += fmt::format(
      "<text class=\"note\" x=\"130\" y=\"{:.1f}\" font-size=\"5\">{} · {} · fabric {:.0f} mm "
      "wide, {:.0f} mm used cutting every piece from one layer · efficiency {:.0f} % · seam "
      "allowance included · true scale (mm)</text>\n",
      y + 4, markup_escape(sheet.title), markup_escape(pieces_summary(piece_counts(sheet))), width,
      kMm * layout.length_used, 100 * layout.efficiency);
  const bool folds = std::any_of(layout.pieces.begin(), layout.pieces.end(),
                                 [](const auto& piece) { return piece.on_fold; });
  if (layout.pairs > 0 || folds)
    svg += fmt::format(
        "<text class=\"note\" x=\"130\" y=\"{:.1f}\" font-size=\"5\">this sheet, {:.0f} mm "
        "long, draws {}{}{}</text>\n",
        y + 11, length,
        layout.pairs > 0 ? "each cut 2 piece once (cut twice, the second turned over)" : "",
        layout.pairs > 0 && folds ? " and " : "",
        folds ? "each CUT 1 ON FOLD piece as its half (cut both halves, the fold along the grain)"
              : "");
  svg += "</svg>\n";
  return svg;
}

std::string pattern_dxf(const PatternSheet& sheet) {
  // DXF R12 (AC1009) text, the version AAMA/ASTM D6673 exchange files use.
  std::string dxf;
  const auto pair = [&](int code, const std::string& value) {
    dxf += fmt::format("{}\n{}\n", code, value);
  };
  const auto num = [&](int code, double value) { pair(code, fmt::format("{:.3f}", value)); };
  const auto polyline = [&](const std::string& layer, const Eigen::MatrixX2d& p) {
    pair(0, "POLYLINE");
    pair(8, layer);
    pair(66, "1");
    pair(70, "1");  // closed
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      pair(0, "VERTEX");
      pair(8, layer);
      num(10, kMm * p(i, 0));
      num(20, kMm * p(i, 1));
    }
    pair(0, "SEQEND");
    pair(8, layer);
  };
  const auto line = [&](const std::string& layer, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    pair(0, "LINE");
    pair(8, layer);
    num(10, kMm * a.x());
    num(20, kMm * a.y());
    num(11, kMm * b.x());
    num(21, kMm * b.y());
  };
  const auto text = [&](const std::string& layer, const Eigen::Vector2d& at, double height,
                        const std::string& value) {
    pair(0, "TEXT");
    pair(8, layer);
    num(10, kMm * at.x());
    num(20, kMm * at.y());
    num(40, height);
    pair(1, value);
  };
  pair(0, "SECTION");
  pair(2, "HEADER");
  pair(9, "$ACADVER");
  pair(1, "AC1009");
  pair(9, "$INSUNITS");
  pair(70, "4");  // millimetres
  pair(9, "$MEASUREMENT");
  pair(70, "1");  // metric
  pair(0, "ENDSEC");
  pair(0, "SECTION");
  pair(2, "TABLES");
  pair(0, "TABLE");
  pair(2, "LAYER");
  pair(70, "7");
  for (const char* layer : {"1", "4", "6", "7", "14", "15"}) {
    pair(0, "LAYER");
    pair(2, layer);
    pair(70, "0");
    pair(62, "7");
    pair(6, "CONTINUOUS");
  }
  pair(0, "ENDTAB");
  pair(0, "ENDSEC");
  pair(0, "SECTION");
  pair(2, "BLOCKS");
  for (const garment::PatternPiece& piece : sheet.layout.pieces) {
    // Its mirror pair's block (cut twice), or cut with its fold piece.
    if (piece.quantity == 0) continue;
    const std::string name = piece_name(sheet, piece);
    pair(0, "BLOCK");
    pair(8, "0");
    pair(2, name);
    pair(70, "0");
    num(10, 0);
    num(20, 0);
    pair(3, name);
    polyline("1", piece.cutting);        // boundary: the cutting line
    polyline("14", piece.curve.points);  // sewing line, the smooth curve densified
    line("7", piece.grain_start, piece.grain_end);
    if (piece.on_fold) line("6", piece.fold_start, piece.fold_end);  // mirror (fold) line
    for (const garment::PatternNotch& n : piece.notches) {
      const auto [a, b] = notch_segment(n);
      line("4", a, b);
    }
    const Eigen::Vector2d at =
        0.5 * (piece.grain_start + piece.grain_end) + Eigen::Vector2d(0.01, 0);
    const double h = 5;  // mm
    text("1", at, h, "Piece Name: " + name);
    text("15", at - Eigen::Vector2d(0, 0.008), h,
         "Material: " + sheet.fabrics[static_cast<size_t>(piece.panel)]);
    text("15", at - Eigen::Vector2d(0, 0.016), h,
         piece.on_fold ? "Quantity: 1 (cut on fold)" : fmt::format("Quantity: {}", piece.quantity));
    text("15", at - Eigen::Vector2d(0, 0.024), h,
         fmt::format("Seam allowance: {} mm", allowance_mm(piece)));
    if (const std::string partner = mirror_partner(sheet, name); !partner.empty())
      text("15", at - Eigen::Vector2d(0, 0.032), h,
           piece.quantity == 2 ? "Mirror pair: " + partner + " (cut 2, the second turned over)"
                               : "Mirror pair: " + partner);
    pair(0, "ENDBLK");
    pair(8, "0");
  }
  pair(0, "ENDSEC");
  pair(0, "SECTION");
  pair(2, "ENTITIES");
  for (const garment::PatternPiece& piece : sheet.layout.pieces) {
    if (piece.quantity == 0) continue;
    pair(0, "INSERT");
    pair(8, "0");
    pair(2, piece_name(sheet, piece));
    num(10, kMm * piece.placement.x());
    num(20, kMm * piece.placement.y());
  }
  pair(0, "ENDSEC");
  pair(0, "EOF");
  return dxf;
}

namespace {

nlohmann::json points_mm(const Eigen::MatrixX2d& p) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    out.push_back(
        {std::round(kMm * p(i, 0) * 1000) / 1000, std::round(kMm * p(i, 1) * 1000) / 1000});
  return out;
}

// The outline points the smooth sewing line keeps as corners (indices into sewing_line).
nlohmann::json corner_points(const garment::SmoothOutline& curve) {
  nlohmann::json out = nlohmann::json::array();
  for (size_t k = 0; k < curve.corner.size(); ++k)
    if (curve.corner[k]) out.push_back(k);
  return out;
}

nlohmann::json point_mm(const Eigen::Vector2d& p) {
  return {std::round(kMm * p.x() * 1000) / 1000, std::round(kMm * p.y() * 1000) / 1000};
}

nlohmann::json distortion_json(const garment::FlatDistortion& d) {
  return {{"length_max", d.length_max},
          {"length_mean", d.length_mean},
          {"length_p95", d.length_p95},
          {"area_max", d.area_max},
          {"area_mean", d.area_mean},
          {"worst_near_m", {d.worst_point.x(), d.worst_point.y(), d.worst_point.z()}},
          {"dome_rad", d.dome},
          {"saddle_rad", d.saddle}};
}

// The centre line held straight by the flattening (FlatPanel::centre_run), with what the free
// flattening gave for comparison; null for a piece flattened freely.
nlohmann::json centre_line_json(const garment::FlatPanel& flat) {
  if (flat.centre_off_grain_deg < 0) return nullptr;
  // How far a fold turns the piece's threads off its mean warp (null when no held flattening
  // was made), and whether a fitted piece kept its centre seam for it.
  const nlohmann::json turn =
      flat.fold_turn_deg >= 0 ? nlohmann::json(flat.fold_turn_deg) : nlohmann::json(nullptr);
  if (flat.centre_run.empty())
    return {{"held_straight", false},
            {"off_grain_deg", flat.centre_off_grain_deg},
            {"fold_turn_deg", turn},
            {"seam_for_fold_turn", flat.fold_turn_refused}};
  return {{"held_straight", true},
          {"off_grain_deg", flat.centre_off_grain_deg},
          {"fold_turn_deg", turn},
          {"seam_for_fold_turn", false},
          {"free_bow_mm", kMm * flat.free_centre_bow},
          {"free_distortion", distortion_json(flat.free_distortion)}};
}

// A seam side's polyline as flattened (m, before ease).
Eigen::MatrixX2d flat_seam_side(const PatternSheet& sheet, int panel,
                                const std::vector<int>& vertices) {
  const garment::FlatPanel& flat = sheet.pattern.panels[static_cast<size_t>(panel)];
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(vertices.size()), 2);
  for (size_t k = 0; k < vertices.size(); ++k)
    out.row(static_cast<Eigen::Index>(k)) = flat.uv.row(vertices[k]);
  return out;
}

// A seam side's polyline in its piece's frame (m, ease applied): the piece's sewing points.
Eigen::MatrixX2d seam_side(const PatternSheet& sheet, int panel, const std::vector<int>& vertices) {
  const garment::FlatPanel& flat = sheet.pattern.panels[static_cast<size_t>(panel)];
  const garment::PatternPiece& piece = sheet.layout.pieces[static_cast<size_t>(panel)];
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(vertices.size()), 2);
  for (size_t k = 0; k < vertices.size(); ++k)
    out.row(static_cast<Eigen::Index>(k)) = piece.sewing.row(
        std::find(flat.boundary.begin(), flat.boundary.end(), vertices[k]) - flat.boundary.begin());
  return out;
}

// A seam side on its piece's smooth sewing line (m, piece frame, ease applied): the densified
// curve from the side's first outline point to its last, in the side's order.
Eigen::MatrixX2d curve_side(const PatternSheet& sheet, int panel,
                            const std::vector<int>& vertices) {
  const garment::FlatPanel& flat = sheet.pattern.panels[static_cast<size_t>(panel)];
  const garment::SmoothOutline& curve = sheet.layout.pieces[static_cast<size_t>(panel)].curve;
  const auto n = static_cast<Eigen::Index>(flat.boundary.size());
  const auto index = [&](int v) {
    return static_cast<Eigen::Index>(std::find(flat.boundary.begin(), flat.boundary.end(), v) -
                                     flat.boundary.begin());
  };
  const Eigen::Index first = index(vertices.front());
  const bool forward = vertices.size() < 2 || index(vertices[1]) == (first + 1) % n;
  const Eigen::Index m = curve.points.rows();
  std::vector<Eigen::Index> rows;
  const Eigen::Index spans = static_cast<Eigen::Index>(vertices.size()) - 1;
  Eigen::Index row = curve.at[static_cast<size_t>(first)];
  rows.push_back(row);
  for (Eigen::Index s = 0; s < spans; ++s) {
    const Eigen::Index from = forward ? (first + s) % n : (first - s + n) % n;
    const Eigen::Index to = forward ? (from + 1) % n : (from - 1 + n) % n;
    const Eigen::Index end = curve.at[static_cast<size_t>(to)];
    while (row != end) {
      row = forward ? (row + 1) % m : (row - 1 + m) % m;
      rows.push_back(row);
    }
  }
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(rows.size()), 2);
  for (size_t k = 0; k < rows.size(); ++k)
    out.row(static_cast<Eigen::Index>(k)) = curve.points.row(rows[k]);
  return out;
}

double polyline_length(const Eigen::MatrixX2d& p) {
  double l = 0;
  for (Eigen::Index i = 1; i < p.rows(); ++i) l += (p.row(i) - p.row(i - 1)).norm();
  return l;
}

}  // namespace

nlohmann::json ease_json(const garment::PanelEase& ease) {
  if (ease.isotropic()) return ease.warp;
  return {{"warp", ease.warp}, {"weft", ease.weft}};
}

nlohmann::json pattern_json(const PatternSheet& sheet) {
  const garment::PatternLayout& layout = sheet.layout;
  const PieceCounts counts = piece_counts(sheet);
  nlohmann::json pieces = nlohmann::json::array();
  for (const garment::PatternPiece& piece : layout.pieces) {
    const garment::FlatPanel& flat = sheet.pattern.panels[static_cast<size_t>(piece.panel)];
    nlohmann::json notches = nlohmann::json::array();
    for (const garment::PatternNotch& n : piece.notches)
      notches.push_back({{"at", point_mm(n.point)},
                         {"outward", {n.normal.x(), n.normal.y()}},
                         {"kind", n.balance ? "balance" : "junction"}});
    nlohmann::json allowances = nlohmann::json::array();
    for (const garment::AllowanceRun& run : piece.allowances)
      allowances.push_back(
          {{"first_edge", run.first}, {"last_edge", run.last}, {"mm", kMm * run.allowance}});
    pieces.push_back(
        {{"id", flat.id},
         {"fabric", sheet.fabrics[static_cast<size_t>(piece.panel)]},
         {"ease", ease_json(piece.ease)},
         {"gathered", !piece.ease.isotropic()},
         {"gather_ratio",
          std::max(piece.ease.warp, piece.ease.weft) / std::min(piece.ease.warp, piece.ease.weft)},
         {"seam_allowance_mm", kMm * piece.allowance},
         {"allowances", allowances},
         {"size_mm", point_mm(piece.size)},
         {"placement_mm", point_mm(piece.placement)},
         {"sewn_area_mm2", kMm * kMm * piece.sewn_area},
         {"cut_area_mm2", kMm * kMm * piece.cut_area},
         {"surface_area_mm2", kMm * kMm * flat.area_3d},
         {"sewing_line", points_mm(piece.sewing)},
         {"sewing_curve", points_mm(piece.curve.points)},
         {"sewing_corners", corner_points(piece.curve)},
         {"on_fold", piece.on_fold},
         {"fold_line", piece.on_fold
                           ? nlohmann::json{point_mm(piece.fold_start), point_mm(piece.fold_end)}
                           : nlohmann::json()},
         {"folded_into", piece.folded_into >= 0
                             ? sheet.pattern.panels[static_cast<size_t>(piece.folded_into)].id
                             : std::string()},
         {"cutting_line", points_mm(piece.cutting)},
         {"grain_line", {point_mm(piece.grain_start), point_mm(piece.grain_end)}},
         {"notches", notches},
         {"distortion", distortion_json(flat.distortion)},
         {"centre_line", centre_line_json(flat)},
         {"iterations", flat.iterations},
         {"warning", flat.warning},
         {"mirror_pair", mirror_partner(sheet, flat.id)},
         {"quantity", piece.quantity},
         {"drawn_as", piece.drawn_as >= 0
                          ? piece_name(sheet, layout.pieces[static_cast<size_t>(piece.drawn_as)])
                          : flat.id}});
  }
  nlohmann::json seams = nlohmann::json::array();
  for (const garment::PatternSeam& seam : sheet.pattern.seams) {
    const Eigen::MatrixX2d a = seam_side(sheet, seam.panel_a, seam.vertices_a);
    const Eigen::MatrixX2d b = seam_side(sheet, seam.panel_b, seam.vertices_b);
    const double la = polyline_length(a), lb = polyline_length(b);
    const Eigen::MatrixX2d ca = curve_side(sheet, seam.panel_a, seam.vertices_a);
    const Eigen::MatrixX2d cb = curve_side(sheet, seam.panel_b, seam.vertices_b);
    // What the ease made of each side's flattened length (1: as flattened; e: eased by e; a
    // gathered piece's side between its warp and weft factors, by the side's direction).
    const double ga = la / polyline_length(flat_seam_side(sheet, seam.panel_a, seam.vertices_a));
    const double gb = lb / polyline_length(flat_seam_side(sheet, seam.panel_b, seam.vertices_b));
    seams.push_back({{"a", sheet.pattern.panels[static_cast<size_t>(seam.panel_a)].id},
                     {"b", sheet.pattern.panels[static_cast<size_t>(seam.panel_b)].id},
                     {"length_3d_mm", kMm * seam.length_3d},
                     {"length_a_mm", kMm * la},
                     {"length_b_mm", kMm * lb},
                     {"flattening_mismatch", seam.mismatch()},
                     {"ease_difference", std::abs(la - lb) / std::max(la, lb)},
                     {"ease_a", ga},
                     {"ease_b", gb},
                     {"gather", std::max(ga, gb) / std::min(ga, gb)},
                     {"balance_notches", seam.balance},
                     {"polyline_a", points_mm(a)},
                     {"polyline_b", points_mm(b)},
                     {"curve_a", points_mm(ca)},
                     {"curve_b", points_mm(cb)},
                     {"curve_length_a_mm", kMm * polyline_length(ca)},
                     {"curve_length_b_mm", kMm * polyline_length(cb)}});
  }
  return {{"format", "sketchdrape/1 pattern"},
          {"sketch", sheet.title},
          {"units", "mm"},
          {"frame",
           "pieces: x across, y along the warp (grain), seen from the right side; fabric: "
           "x across the width, y along the bolt from the cut end"},
          {"fabric_width_mm", kMm * layout.fabric_width},
          {"fabric_length_mm", kMm * layout.length_used},
          {"efficiency", layout.efficiency},
          {"sheet_length_mm", kMm * layout.sheet_length},
          {"sheet_efficiency", layout.sheet_efficiency},
          {"mirror_pairs", layout.pairs},
          {"pieces_to_cut", counts.to_cut},
          {"pieces_drawn", counts.drawn},
          {"fold_pieces", counts.on_fold},
          {"pieces_summary", pieces_summary(counts)},
          {"pieces", pieces},
          {"seams", seams},
          {"warnings", sheet.pattern.warnings}};
}

nlohmann::json pattern_summary(const PatternSheet& sheet) {
  const PieceCounts counts = piece_counts(sheet);
  nlohmann::json pieces = nlohmann::json::array();
  for (const garment::FlatPanel& flat : sheet.pattern.panels)
    pieces.push_back({{"id", flat.id}, {"distortion", distortion_json(flat.distortion)}});
  double worst = 0;
  for (const garment::PatternSeam& seam : sheet.pattern.seams)
    worst = std::max(worst, seam.mismatch());
  return {{"pieces", pieces},
          {"seams", sheet.pattern.seams.size()},
          {"worst_seam_mismatch", worst},
          {"fabric_width_mm", kMm * sheet.layout.fabric_width},
          {"fabric_length_mm", kMm * sheet.layout.length_used},
          {"efficiency", sheet.layout.efficiency},
          {"sheet_length_mm", kMm * sheet.layout.sheet_length},
          {"mirror_pairs", sheet.layout.pairs},
          {"pieces_to_cut", counts.to_cut},
          {"pieces_drawn", counts.drawn},
          {"fold_pieces", counts.on_fold},
          {"pieces_summary", pieces_summary(counts)},
          {"warnings", sheet.pattern.warnings},
          {"timing_ms", {{"flatten", sheet.flatten_ms}, {"layout", sheet.layout_ms}}}};
}

void stage_pattern(const PatternSheet& sheet, const std::filesystem::path& dir,
                   StagedOutputs& outputs) {
  outputs.stage(dir / "pattern.svg", pattern_svg(sheet));
  outputs.stage(dir / "pattern.dxf", pattern_dxf(sheet));
  outputs.stage(dir / "pattern.json", pattern_json(sheet).dump(1) + "\n");
}

}  // namespace sd::app
