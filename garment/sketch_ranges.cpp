#include "garment/sketch_ranges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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
      "{} is too far from the body ({:.2f} m tall): points must lie within {:.2f} m of it, and {}",
      what, reach.height, kBodyMarginHeights * reach.height,
      out_of_range_sentence(p[axis], reach.low[axis], reach.high[axis],
                            fmt::format("{} =", kAxis[axis])));
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

std::string out_of_range_sentence(double value, double low, double high, const std::string& what) {
  std::string sentence =
      fmt::format("{} {:.6g} m is outside {:.6g} .. {:.6g} m", what, value, low, high);
  // A hint only where the reading is a size a garment or body has (within ±2 body heights).
  const auto plausible = [&](double v) {
    return v >= low && v <= high && std::abs(v) <= 2 * kMaxBodyHeight;
  };
  const bool as_cm = plausible(value / 100);
  const bool as_mm = plausible(value / 1000);
  if (as_cm)
    sentence += fmt::format(
        "; lengths and coordinates are in metres: if you typed centimetres, "
        "{:.6g} cm is {:.6g} m",
        value, value / 100);
  else if (as_mm)
    sentence += fmt::format(
        "; lengths and coordinates are in metres: if you typed millimetres, "
        "{:.6g} mm is {:.6g} m",
        value, value / 1000);
  // A tenth in range reads as a decimal point one place off (4.2 for 0.42) as much as a unit:
  // offer both rather than assert centimetres.
  if ((as_cm || as_mm) && plausible(value / 10))
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

void check_panel_sizes(const GarmentRequest& sketch, const std::vector<double>& boundary_edges,
                       const std::vector<std::string>& panel_paths,
                       const std::vector<std::string>& panel_ids) {
  double total = 0;
  size_t largest = 0;
  for (size_t p = 0; p < boundary_edges.size(); ++p) {
    total += estimated_quads(boundary_edges[p]);
    if (boundary_edges[p] > boundary_edges[largest]) largest = p;
  }
  if (total <= kMaxGarmentQuads || boundary_edges.empty()) return;
  // Quads scale with 1/edge_length²: this factor longer edges would fit.
  const double factor = std::sqrt(total / kMaxGarmentQuads);
  sketch.fail(
      panel_paths[largest],
      fmt::format("the garment would have up to {:.3g} quads (panel '{}' alone has {:.0f} "
                  "boundary edges), more than the {:.0f} this program meshes; use edges "
                  "about {:.2g} times longer (\"edge_length\") or fewer \"edges\"",
                  total, panel_ids[largest], boundary_edges[largest], kMaxGarmentQuads, factor));
}

}  // namespace sd::garment
