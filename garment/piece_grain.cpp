#include "garment/piece_grain.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace sd::garment {

PieceShape piece_shape(const FlatPanel& piece) {
  // Area-weighted centroid and second moments of the triangles (each by its centroid and its own
  // spread: the exact moments of a uniform triangle, (Σ vᵢvᵢᵀ + s sᵀ) A / 12 with s = Σ vᵢ).
  double area = 0.0;
  Eigen::Vector2d first = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  for (Eigen::Index t = 0; t < piece.triangles.rows(); ++t) {
    const Eigen::Vector2d a = piece.uv.row(piece.triangles(t, 0)).transpose();
    const Eigen::Vector2d b = piece.uv.row(piece.triangles(t, 1)).transpose();
    const Eigen::Vector2d c = piece.uv.row(piece.triangles(t, 2)).transpose();
    const Eigen::Vector2d ab = b - a, ac = c - a;
    const double at = 0.5 * std::abs(ab.x() * ac.y() - ab.y() * ac.x());
    const Eigen::Vector2d s = a + b + c;
    area += at;
    first += at * s / 3.0;
    second +=
        at / 12.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  PieceShape shape;
  if (!(area > 0.0)) return shape;
  const Eigen::Vector2d centre = first / area;
  const Eigen::Matrix2d covariance = second / area - centre * centre.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(covariance);
  const Eigen::Vector2d along = solver.eigenvectors().col(1);  // the larger eigenvalue's
  const Eigen::Vector2d across(-along.y(), along.x());
  double lo = std::numeric_limits<double>::max(), hi = -lo, wlo = lo, whi = -lo;
  for (Eigen::Index v = 0; v < piece.uv.rows(); ++v) {
    const Eigen::Vector2d p = piece.uv.row(v).transpose() - centre;
    lo = std::min(lo, p.dot(along)), hi = std::max(hi, p.dot(along));
    wlo = std::min(wlo, p.dot(across)), whi = std::max(whi, p.dot(across));
  }
  shape.length = hi - lo;
  shape.width = whi - wlo;
  // +y turned counter-clockwise by θ is (−sin θ, cos θ); an axis has no sign, so θ in −90 .. 90.
  double angle = std::atan2(-along.x(), along.y()) * 180.0 / std::numbers::pi;
  if (angle > 90.0) angle -= 180.0;
  if (angle <= -90.0) angle += 180.0;
  shape.angle_deg = angle;
  return shape;
}

std::string cross_grain_warning(const FlatPanel& piece, const GarmentPanel& panel,
                                const PieceGrainLimits& limits) {
  // A turned grain is the designer's own (a bias cut), and says so in the file.
  if (panel.grain_turn_deg != 0.0) return "";
  const PieceShape shape = piece_shape(piece);
  if (!(shape.width > 0.0) || shape.length < limits.min_length_ratio * shape.width) return "";
  if (std::abs(shape.angle_deg) <= limits.max_angle_deg) return "";
  // The turn of the warp that lays it along the length: the warp turned counter-clockwise (seen
  // from outside, as the piece is drawn) by the long axis's angle.
  const int turn = static_cast<int>(std::lround(shape.angle_deg));
  return fmt::format(
      "panel '{}': a long narrow piece ({:.0f} × {:.0f} mm, like a strap or a waistband) is cut "
      "with its length {:.0f}° off the grain line (its grain is \"{}\", which runs across it "
      "here): cut so it stretches along its length, where the weft gives more than the warp. To "
      "lay its length along the grain give the panel \"grain\": {} (or {{\"along\": \"{}\", "
      "\"turn\": {}}}); for a bias cut give 45 or -45; a collar or a cuff cut across the grain on "
      "purpose can stay as it is",
      panel.id, 1e3 * shape.length, 1e3 * shape.width, std::abs(shape.angle_deg), panel.grain, turn,
      panel.grain, turn);
}

}  // namespace sd::garment
