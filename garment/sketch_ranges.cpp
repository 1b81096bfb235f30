#include "garment/sketch_ranges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string_view>
#include <tuple>
#include <vector>

#include "garment/stroke_projection.hpp"

namespace sd::garment {
namespace {

// World axis names for messages.
constexpr const char* kAxis[] = {"x", "y", "z"};

// The body's box grown by the margin, metres.
struct Reach {
  Eigen::Vector3d low, high;
  double height = 0;
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= low.array()).all() && (p.array() <= high.array()).all();
  }
};

// The sentence for world point `p` outside `reach`, naming the first axis that is out.
std::string outside_sentence(const Eigen::Vector3d& p, const Reach& reach,
                             const std::string& what) {
  int axis = 0;
  for (int k = 0; k < 3; ++k)
    if (p[k] < reach.low[k] || p[k] > reach.high[k]) {
      axis = k;
      break;
    }
  return fmt::format(
      "{} is too far from the body ({}): points must lie within {:.2f} m of it, and {}", what,
      body_height_clause(reach.height), kBodyMarginHeights * reach.height,
      out_of_range_sentence(p[axis], reach.low[axis], reach.high[axis],
                            fmt::format("{} =", kAxis[axis]),
                            {reach.low[axis] + kBodyMarginHeights * reach.height,
                             reach.high[axis] - kBodyMarginHeights * reach.height}));
}

// The sentence for a landmark point `p` outside `reach` along `axis`, given as landmark `name` at
// `at` (on this body) plus `offset` as written: the offset is the number typed, so it is quoted
// with the readings of it in millimetres and centimetres that bring the point within reach (trial
// 43, P15: an offset typed as [-36, -1, 0] for 36 mm was told "if you typed centimetres, -35.8236
// cm is -0.358236 m", the reading of the sum). With "drawn_on" the offset is scaled for this body
// (p - at), and each reading scales it alike.
std::string offset_sentence(const Eigen::Vector3d& p, int axis, const Reach& reach,
                            const std::string& what, const std::string& name,
                            const Eigen::Vector3d& at, const Eigen::Vector3d& offset) {
  std::string readings;
  for (const auto& [unit, symbol, scale] :
       {std::tuple{"millimetres", "mm", 1e-3}, std::tuple{"centimetres", "cm", 1e-2}}) {
    const double moved = at[axis] + (p[axis] - at[axis]) * scale;
    if (moved < reach.low[axis] || moved > reach.high[axis]) continue;
    readings += fmt::format("{} {}, {:g} {} is {:g} m", readings.empty() ? "if you typed" : "; if",
                            unit, offset[axis], symbol, offset[axis] * scale);
  }
  return fmt::format(
      "{} is too far from the body ({}): it is landmark '{}' at ({:.3f}, {:.3f}, {:.3f}) m plus "
      "the offset [{:g}, {:g}, {:g}], so its {} = {:.6g} m is outside {:.6g} .. {:.6g} m; "
      "offsets are in metres{}",
      what, body_height_clause(reach.height), name, at.x(), at.y(), at.z(), offset.x(), offset.y(),
      offset.z(), kAxis[axis], p[axis], reach.low[axis], reach.high[axis],
      readings.empty() ? "" : ": " + readings);
}

// Length of a control polygon, metres (the spline through the points is about as long).
template <int D>
double polygon_length(const std::vector<Eigen::Matrix<double, D, 1>>& points, bool closed) {
  double length = 0;
  for (size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  if (closed && points.size() > 2) length += (points.front() - points.back()).norm();
  return length;
}

}  // namespace

std::string body_height_clause(double height) {
  // A body far shorter or taller than a person (trial 40: "height": 0.1) is the likelier slip
  // than the point: asked first.
  if (height < kShortestPerson || height > kTallestPerson)
    return fmt::format(
        "{:.2f} m tall: is that meant? A body's \"height\" is in metres, a grown figure's 1.5-1.9",
        height);
  return fmt::format("{:.2f} m tall", height);
}

std::string out_of_range_sentence(double value, double low, double high, const std::string& what,
                                  UsualRange usual) {
  std::string sentence =
      fmt::format("{} {:.6g} m is outside {:.6g} .. {:.6g} m", what, value, low, high);
  // A hint only where the reading is a size a garment or body has (within ±2 body heights).
  const auto plausible = [&](double v) {
    return v >= low && v <= high && std::abs(v) <= 2 * kMaxBodyHeight;
  };
  const auto is_usual = [&](double v) { return v >= usual.low && v <= usual.high; };
  struct Reading {
    const char* unit;
    const char* symbol;
    double metres;
  };
  std::vector<Reading> readings;
  for (const Reading& r :
       {Reading{"centimetres", "cm", value / 100}, Reading{"millimetres", "mm", value / 1000}})
    if (plausible(r.metres)) readings.push_back(r);
  // Centimetres alone when that is a usual value (130 for a hem at 1.3 m); else the usual
  // reading first, the other after it (a seam allowance of 10: 10 mm, or 10 cm, a deep hem).
  if (!readings.empty() && readings[0].symbol == std::string_view("cm") &&
      is_usual(readings[0].metres))
    readings.resize(1);
  std::stable_sort(readings.begin(), readings.end(), [&](const Reading& a, const Reading& b) {
    return is_usual(a.metres) && !is_usual(b.metres);
  });
  if (!readings.empty()) {
    sentence += fmt::format(
        "; lengths and coordinates are in metres: if you typed {}, {:.6g} {} is {:.6g} m",
        readings[0].unit, value, readings[0].symbol, readings[0].metres);
    if (readings.size() > 1)
      sentence += fmt::format(" (if {}, {:.6g} {} is {:.6g} m)", readings[1].unit, value,
                              readings[1].symbol, readings[1].metres);
  }
  // A tenth in range reads as a decimal point one place off (4.2 for 0.42) as much as a unit:
  // offer both rather than assert centimetres.
  if (!readings.empty() && plausible(value / 10))
    sentence += fmt::format("; or, if the decimal point slipped, {:.6g} m", value / 10);
  return sentence;
}

void check_against_body(const GarmentRequest& sketch, const meshing::BoundingBox& body_box) {
  Reach reach;
  reach.height = body_box.extent().y();
  const double margin = kBodyMarginHeights * reach.height;
  reach.low = body_box.min - Eigen::Vector3d::Constant(margin);
  reach.high = body_box.max + Eigen::Vector3d::Constant(margin);

  double total_length = 0;
  for (const CurveSpec& curve : sketch.curves) {
    const std::string key = curve.is_3d() ? "/points3d" : "/points";
    if (curve.view.kind == ViewKind::kCamera && !curve.is_3d()) {
      if (!reach.contains(curve.view.camera.target))
        sketch.fail(curve.json_path + "/view/camera/target",
                    outside_sentence(curve.view.camera.target, reach, "the camera's target"));
    }
    const ViewFrame frame = view_frame(curve.view);
    const size_t n = curve.is_3d() ? curve.points3d.size() : curve.points.size();
    for (size_t i = 0; i < n; ++i) {
      const std::string path = fmt::format("{}{}/{}", curve.json_path, key, i);
      if (curve.is_3d()) {
        const Eigen::Vector3d& p = curve.points3d[i];
        if (i < curve.landmark_name.size() && !curve.landmark_name[i].empty())
          for (int k = 0; k < 3; ++k)
            if (p[k] < reach.low[k] || p[k] > reach.high[k])
              sketch.fail(
                  fmt::format("{}/offset/{}", path, k),
                  offset_sentence(p, k, reach, fmt::format("point {} of curve '{}'", i, curve.id),
                                  curve.landmark_name[i], curve.landmark_at[i],
                                  curve.landmark_offset[i]));
        for (int k = 0; k < 3; ++k)
          if (p[k] < reach.low[k] || p[k] > reach.high[k])
            sketch.fail(
                fmt::format("{}/{}", path, k),
                outside_sentence(p, reach, fmt::format("point {} of curve '{}'", i, curve.id)));
        continue;
      }
      const Eigen::Vector2d& uv = curve.points[i];
      const Eigen::Vector3d p = frame.plane_point(uv);
      if (reach.contains(p)) continue;
      // Name the 2D coordinate that carries the offending world axis (orthographic views map
      // u and v onto world axes; a camera's plane is tilted, so name the point).
      std::string where = path;
      if (!frame.perspective) {
        const Eigen::Index v_axis = 1;
        Eigen::Index u_axis = 0;
        frame.right.cwiseAbs().maxCoeff(&u_axis);
        if (p[v_axis] < reach.low[v_axis] || p[v_axis] > reach.high[v_axis])
          where += "/1";
        else if (p[u_axis] < reach.low[u_axis] || p[u_axis] > reach.high[u_axis])
          where += "/0";
      }
      sketch.fail(where, outside_sentence(p, reach,
                                          fmt::format("point {} of curve '{}' ({} view)", i,
                                                      curve.id, curve.view.name())));
    }
    const double length = curve.is_3d() ? polygon_length<3>(curve.points3d, curve.closed)
                                        : polygon_length<2>(curve.points, curve.closed);
    if (length > kMaxCurveLengthHeights * reach.height)
      sketch.fail(curve.json_path + key,
                  fmt::format("curve '{}' is {:.1f} m long through its points, more than {:g} "
                              "times the body's height ({:.2f} m); a garment's curves are "
                              "shorter: check the coordinates (metres)",
                              curve.id, length, kMaxCurveLengthHeights, reach.height));
    total_length += length;
  }
  if (total_length > kMaxTotalCurveLengthHeights * reach.height)
    sketch.fail("/curves", fmt::format("the curves are {:.0f} m long together, more than {:g} "
                                       "times the body's height ({:.2f} m)",
                                       total_length, kMaxTotalCurveLengthHeights, reach.height));

  for (const PanelSpec& panel : sketch.panels) {
    if (!panel.seed) continue;
    const SeedSpec& seed = *panel.seed;
    if (seed.point3d) {
      if (!reach.contains(*seed.point3d))
        sketch.fail(seed.json_path + "/point3d",
                    outside_sentence(*seed.point3d, reach,
                                     fmt::format("the seed of panel '{}'", panel.id)));
    } else if (seed.point) {
      const Eigen::Vector3d p = view_frame(seed.view).plane_point(*seed.point);
      if (!reach.contains(p))
        sketch.fail(seed.json_path + "/point",
                    outside_sentence(p, reach, fmt::format("the seed of panel '{}'", panel.id)));
    }
  }
}

double estimated_quads(double boundary_edges) {
  return boundary_edges * boundary_edges / 16.0;
}

namespace {
// A panel's surface over its fan's area (fan_area): over the examples and the design corpus at
// their own edge lengths the meshes had 0.93-1.38 times the quads of the fan's area over the mean
// boundary edge squared, 1.11 in the median (the fan cuts across a panel curving round the body).
constexpr double kSurfaceOverFan = 1.1;

// "378,000": a count to three figures, with thousands separated.
std::string rounded_count(double n) {
  const double scale = std::pow(10.0, std::max(0.0, std::floor(std::log10(n)) - 2));
  std::string digits = fmt::format("{:.0f}", std::round(n / scale) * scale);
  for (int k = static_cast<int>(digits.size()) - 3; k > 0; k -= 3)
    digits.insert(static_cast<size_t>(k), ",");
  return digits;
}
}  // namespace

double estimated_quads(const PanelSize& panel) {
  const double bound = estimated_quads(panel.boundary_edges);
  if (panel.boundary_edges <= 0 || panel.boundary_length <= 0) return bound;
  const double edge = panel.boundary_length / panel.boundary_edges;
  return std::min(bound, kSurfaceOverFan * panel.area / (edge * edge));
}

double fan_area(const std::vector<Eigen::Vector3d>& outline) {
  if (outline.size() < 3) return 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : outline) centre += p;
  centre /= static_cast<double>(outline.size());
  double area = 0;
  for (size_t k = 0; k < outline.size(); ++k)
    area += 0.5 * (outline[k] - centre).cross(outline[(k + 1) % outline.size()] - centre).norm();
  return area;
}

std::vector<std::string> fine_edge_warnings(const GarmentRequest& sketch,
                                            const std::vector<PanelSize>& panels) {
  std::vector<std::string> out;
  for (const PanelSize& size : panels) {
    if (size.mirror_copy || !(size.boundary_edges > 0) || !(size.boundary_length > 0)) continue;
    const double edge = size.boundary_length / size.boundary_edges;
    if (!(edge < kCleanEdgeLength * (1 - kCleanEdgeSlack))) continue;
    const double quads = estimated_quads(size);
    const double seconds = quads * kMeshingSecondsPerQuad;
    out.push_back(fmt::format(
        "{}: {}: panel '{}' has edges of {:.1f} mm along its outline, which make about {} "
        "quads of it ({:.3f} m² over the edge squared; meshing takes about {:.0f} s of CPU); "
        "below {:.0f} mm the quad filler was measured to leave slivers, vertices on one spot and "
        "quads inside the body (a 30 x 45 cm panel: clean at 4 mm, 9,348 quads; 6-7 quality "
        "warnings at 2-3 mm, up to 37,395 quads; docs/sketch-format.md, \"Limits\"). Give it an "
        "\"edge_length\" of {:g} or more, or keep this one if the quality gate's warnings after "
        "meshing name nothing in panel '{}' (a smaller panel can be clean finer): this is a "
        "warning, the file is meshed as written",
        sketch.file, size.path, size.id, 1e3 * edge, rounded_count(quads),
        kSurfaceOverFan * size.area, std::max(1.0, seconds), 1e3 * kCleanEdgeLength,
        kCleanEdgeLength, size.id));
  }
  return out;
}

void check_panel_sizes(const GarmentRequest& sketch, const std::vector<PanelSize>& panels) {
  const auto total_quads = [](const std::vector<PanelSize>& sizes) {
    double total = 0;
    for (const PanelSize& size : sizes) total += estimated_quads(size);
    return total;
  };
  const double total = total_quads(panels);
  if (total <= kMaxGarmentQuads || panels.empty()) return;
  size_t largest = 0;
  for (size_t p = 0; p < panels.size(); ++p)
    if (!panels[p].mirror_copy && (panels[largest].mirror_copy ||
                                   estimated_quads(panels[p]) > estimated_quads(panels[largest])))
      largest = p;
  const double seconds = total * kMeshingSecondsPerQuad;
  const auto count = rounded_count;
  const std::string limit = fmt::format(
      "more than the {} this program meshes: meshing them would take about {} of CPU and {:.1f} "
      "GB of memory",
      count(kMaxGarmentQuads),
      seconds < 120 ? fmt::format("{:.0f} s", seconds) : fmt::format("{:.0f} min", seconds / 60),
      total * kMeshingBytesPerQuad / 1e9);

  // Curves whose fixed "edges" cut edges far (over twice) shorter than the rest of the panel's
  // outline (or than the file's edge_length when the whole outline is fixed): with counts that
  // give them that edge, would the garment fit? Then the count is what to change, not the length.
  std::map<int, double> scale;    // curve → the factor its edges should grow by (the largest)
  std::map<int, double> natural;  // curve → the edge its panels give it (m)
  for (const PanelSize& size : panels) {
    double fixed_edges = 0, fixed_length = 0;
    for (const PanelSize::FixedEdges& f : size.fixed)
      fixed_edges += f.edges, fixed_length += f.length;
    const double free_edges = size.boundary_edges - fixed_edges;
    const double edge =
        free_edges > 0.5 ? (size.boundary_length - fixed_length) / free_edges : sketch.edge_length;
    for (const PanelSize::FixedEdges& f : size.fixed) {
      if (!(f.edges > 0) || !(f.length > 0)) continue;
      const double own = f.length / f.edges;
      if (own * 2 < edge && edge / own > scale[f.curve]) {
        scale[f.curve] = edge / own;
        natural[f.curve] = edge;
      }
    }
  }
  if (!scale.empty()) {
    std::vector<PanelSize> fewer = panels;
    for (PanelSize& size : fewer)
      for (PanelSize::FixedEdges& f : size.fixed)
        if (scale.count(f.curve)) {
          const double edges = std::max(1.0, std::round(f.edges / scale[f.curve]));
          size.boundary_edges += edges - f.edges;
          f.edges = edges;
        }
    if (total_quads(fewer) <= kMaxGarmentQuads) {
      // Name the curve that cuts the shortest edges, with the count that gives it its panel's.
      const auto worst =
          std::max_element(scale.begin(), scale.end(),
                           [](const auto& a, const auto& b) { return a.second < b.second; });
      const CurveSpec& curve = sketch.curves[static_cast<size_t>(worst->first)];
      const int edges = *curve.edges;
      const int fits = std::max(1, static_cast<int>(std::lround(edges / worst->second)));
      sketch.fail(curve.json_path + "/edges",
                  fmt::format("curve '{}' is cut into {} edges of {:.2g} m, where the rest of its "
                              "panel has edges of about {:.2g} m: the garment would have about {} "
                              "quads, {}; give it about {} \"edges\" (or none, to take its "
                              "panel's edge length)",
                              curve.id, edges, natural[worst->first] / worst->second,
                              natural[worst->first], count(total), limit, fits));
    }
  }

  // Quads scale with 1/edge_length²: edges this factor longer would fit.
  const double factor = std::sqrt(total / kMaxGarmentQuads);
  const double edge = panels[largest].boundary_length / panels[largest].boundary_edges;
  const double suggested = std::ceil(factor * edge * 1e4) / 1e4;
  // A factor that rounds to 1 ("about 1 times longer") is said as "slightly"; an edge length
  // below the smallest a file may give (a fixed count's edges) is not suggested.
  const std::string longer = factor < 1.5 ? std::string("slightly longer edges")
                                          : fmt::format("edges about {:.2g} times longer", factor);
  const std::string advice =
      suggested >= kMinEdgeLength
          ? fmt::format("use {} (\"edge_length\" {:.2g} m or more) or fewer \"edges\"", longer,
                        suggested)
          : fmt::format("use {}: fewer \"edges\" on the curves that fix them", longer);
  sketch.fail(panels[largest].path,
              fmt::format("the garment would have about {} quads (panel '{}' about {}, with edges "
                          "of {:.3g} m), {}; {}",
                          count(total), panels[largest].id, count(estimated_quads(panels[largest])),
                          edge, limit, advice));
}

}  // namespace sd::garment
