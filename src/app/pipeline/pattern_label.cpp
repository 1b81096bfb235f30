#include "src/app/pipeline/pattern_label.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace sd::app {
namespace {

constexpr double kLargest = 9.0, kSmallest = 2.0;  // mm, the title's font size
constexpr double kFigures = 0.75;                  // the figure lines' size / the title's
constexpr double kMargin = 1.0;                    // mm kept clear of the sewing line

bool inside(const Eigen::MatrixX2d& polygon, const Eigen::Vector2d& p) {
  bool in = false;
  const Eigen::Index n = polygon.rows();
  for (Eigen::Index i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d a = polygon.row(i), b = polygon.row(j);
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
      in = !in;
  }
  return in;
}

// The text block in its own frame (x along the text, y down, origin at the title's baseline
// start): [x0, x1] × [y0, y1] in mm.
struct Block {
  double x0, x1, y0, y1;
};

Block block(const LabelText& text, double size, bool centred) {
  double width = text_width(text.title, size, true);
  for (const std::string& line : text.lines)
    width = std::max(width, text_width(line, kFigures * size, false));
  const double last = text.lines.empty() ? 0.0 : size + 0.9 * size * double(text.lines.size() - 1);
  const double descent = 0.2 * (text.lines.empty() ? size : kFigures * size);
  const double x0 = centred ? -0.5 * width : 0.0;
  return {x0, x0 + width, -0.8 * size, last + descent};
}

Eigen::Vector2d to_sheet(const LabelPlacement& at, double x, double y) {
  return at.along ? Eigen::Vector2d(at.anchor.x() + y, at.anchor.y() - x)
                  : Eigen::Vector2d(at.anchor.x() + x, at.anchor.y() + y);
}

// The block, grown by the margin, inside the outline: points every ≤ 2 mm along its sides inside,
// and no outline vertex within it (a concave corner reaching into the block).
bool fits(const Eigen::MatrixX2d& outline, const LabelPlacement& at, const Block& b) {
  const double x0 = b.x0 - kMargin, x1 = b.x1 + kMargin, y0 = b.y0 - kMargin, y1 = b.y1 + kMargin;
  const auto side = [&](double ax, double ay, double bx, double by) {
    const int steps = std::max(1, int(std::ceil(std::hypot(bx - ax, by - ay) / 2.0)));
    for (int k = 0; k <= steps; ++k) {
      const double t = double(k) / steps;
      if (!inside(outline, to_sheet(at, ax + t * (bx - ax), ay + t * (by - ay)))) return false;
    }
    return true;
  };
  if (!side(x0, y0, x1, y0) || !side(x1, y0, x1, y1) || !side(x1, y1, x0, y1) ||
      !side(x0, y1, x0, y0))
    return false;
  for (Eigen::Index i = 0; i < outline.rows(); ++i) {
    const Eigen::Vector2d d = outline.row(i).transpose() - at.anchor;
    const double x = at.along ? -d.y() : d.x(), y = at.along ? d.x() : d.y();
    if (x > x0 && x < x1 && y > y0 && y < y1) return false;
  }
  return true;
}

Eigen::Vector2d centroid(const Eigen::MatrixX2d& polygon) {
  double area = 0;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (Eigen::Index i = 0, n = polygon.rows(); i < n; ++i) {
    const Eigen::Vector2d a = polygon.row(i), b = polygon.row((i + 1) % n);
    const double cross = a.x() * b.y() - b.x() * a.y();
    area += cross;
    c += cross * (a + b);
  }
  if (std::abs(area) < 1e-12) return polygon.colwise().mean().transpose();
  return c / (3 * area);
}

}  // namespace

double text_width(const std::string& text, double size, bool bold) {
  // UTF-8: count the bytes that start a character.
  const auto chars = std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  });
  return (bold ? 0.6 : 0.56) * size * double(chars);
}

LabelPlacement place_label(const Eigen::MatrixX2d& outline, const Eigen::Vector2d& grain_a,
                           const Eigen::Vector2d& grain_b, const LabelText& text) {
  const Eigen::Vector2d middle = 0.5 * (grain_a + grain_b);
  const Eigen::Vector2d centre = centroid(outline);
  for (double size = kLargest; size >= kSmallest - 1e-9; size *= 0.9) {
    const double gap = 0.6 * size;  // between the grain line and the text
    // In order of preference: beside the grain line's middle (its right, then its left), then
    // centred on the piece; each horizontal, then along the piece.
    for (int where = 0; where < 3; ++where)
      for (const bool along : {false, true}) {
        LabelPlacement at;
        at.size = size;
        at.along = along;
        at.centred = where == 2 || along;
        const Block b = block(text, size, at.centred);
        const double height = b.y1 - b.y0;
        if (where == 2) {
          // The block's middle on the centroid.
          const double dy = -(b.y0 + 0.5 * height);
          at.anchor = along ? Eigen::Vector2d(centre.x() + dy, centre.y())
                            : Eigen::Vector2d(centre.x(), centre.y() + dy);
        } else if (!along) {
          const double x = where == 0 ? middle.x() + gap : middle.x() - gap - (b.x1 - b.x0);
          at.anchor = {x, middle.y()};
        } else {
          // Turned: the block's top (−y) points left; keep it clear of the grain line.
          const double x = where == 0 ? middle.x() + gap - b.y0 : middle.x() - gap - b.y1;
          at.anchor = {x, middle.y()};
        }
        if (fits(outline, at, b)) {
          at.fits = true;
          return at;
        }
      }
  }
  LabelPlacement at;
  at.size = kSmallest;
  at.centred = true;
  const Block b = block(text, kSmallest, true);
  at.anchor = {centre.x(), centre.y() - (b.y0 + 0.5 * (b.y1 - b.y0))};
  return at;
}

}  // namespace sd::app
