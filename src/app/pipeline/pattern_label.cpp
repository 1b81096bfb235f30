#include "src/app/pipeline/pattern_label.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

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

// The text frame turned by turn_deg anticlockwise as seen (SVG's rotate(−turn), y down).
Eigen::Vector2d to_sheet(const LabelPlacement& at, double x, double y) {
  if (at.turn_deg == 0) return {at.anchor.x() + x, at.anchor.y() + y};
  if (at.turn_deg == 90) return {at.anchor.x() + y, at.anchor.y() - x};
  const double a = at.turn_deg * std::numbers::pi / 180, c = std::cos(a), s = std::sin(a);
  return {at.anchor.x() + x * c + y * s, at.anchor.y() - x * s + y * c};
}

// A sheet offset in the text frame (to_sheet's inverse, less the anchor).
Eigen::Vector2d to_text(const LabelPlacement& at, const Eigen::Vector2d& d) {
  if (at.turn_deg == 0) return d;
  if (at.turn_deg == 90) return {-d.y(), d.x()};
  const double a = at.turn_deg * std::numbers::pi / 180, c = std::cos(a), s = std::sin(a);
  return {d.x() * c - d.y() * s, d.x() * s + d.y() * c};
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
    const Eigen::Vector2d t = to_text(at, outline.row(i).transpose() - at.anchor);
    if (t.x() > x0 && t.x() < x1 && t.y() > y0 && t.y() < y1) return false;
  }
  return true;
}

// Whether the segment a-b (the grain line) passes through the block grown by the margin.
bool crosses(const LabelPlacement& at, const Block& b, const Eigen::Vector2d& a,
             const Eigen::Vector2d& c) {
  const int steps = std::max(1, int(std::ceil((c - a).norm())));  // every ≤ 1 mm
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector2d t = to_text(at, a + (c - a) * (double(k) / steps) - at.anchor);
    if (t.x() > b.x0 - kMargin && t.x() < b.x1 + kMargin && t.y() > b.y0 - kMargin &&
        t.y() < b.y1 + kMargin)
      return true;
  }
  return false;
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

// Where a label may sit turned along a strip: points of the piece at least 0.7 of the widest
// inner distance from its outline (the middle of a strip, all along it), each with the turn of
// its nearest outline side, at most 48 of them spread over the piece.
struct Slant {
  Eigen::Vector2d centre;
  double turn_deg;
};

std::vector<Slant> slants(const Eigen::MatrixX2d& outline) {
  const Eigen::Vector2d lo = outline.colwise().minCoeff(), hi = outline.colwise().maxCoeff();
  const double step = std::max(2.0, (hi - lo).maxCoeff() / 80);
  struct Inner {
    Eigen::Vector2d at;
    double depth;
    Eigen::Vector2d side;
  };
  std::vector<Inner> inner;
  double deepest = 0;
  for (double y = lo.y() + 0.5 * step; y < hi.y(); y += step)
    for (double x = lo.x() + 0.5 * step; x < hi.x(); x += step) {
      const Eigen::Vector2d p(x, y);
      if (!inside(outline, p)) continue;
      Inner in{p, std::numeric_limits<double>::infinity(), Eigen::Vector2d::UnitX()};
      for (Eigen::Index i = 0, n = outline.rows(); i < n; ++i) {
        const Eigen::Vector2d a = outline.row(i), b = outline.row((i + 1) % n);
        const Eigen::Vector2d d = b - a;
        const double t = std::clamp((p - a).dot(d) / std::max(d.squaredNorm(), 1e-12), 0.0, 1.0);
        const double gap = (a + t * d - p).norm();
        if (gap < in.depth) in.depth = gap, in.side = d;
      }
      deepest = std::max(deepest, in.depth);
      inner.push_back(in);
    }
  std::erase_if(inner, [&](const Inner& in) { return in.depth < 0.7 * deepest; });
  std::vector<Slant> out;
  const size_t stride = std::max<size_t>(1, (inner.size() + 47) / 48);
  for (size_t i = 0; i < inner.size(); i += stride) {
    // Seen on the sheet (y down), the side's anticlockwise angle, turned to read left to right
    // or upwards.
    double turn = std::atan2(-inner[i].side.y(), inner[i].side.x()) * 180 / std::numbers::pi;
    if (turn > 90) turn -= 180;
    if (turn <= -90) turn += 180;
    out.push_back({inner[i].at, std::round(10 * turn) / 10});  // as the SVG writes it
  }
  return out;
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
  std::vector<Slant> slanted;  // made when the first size fits nowhere else
  for (double size = kLargest; size >= kSmallest - 1e-9; size *= 0.9) {
    const double gap = 0.6 * size;  // between the grain line and the text
    // In order of preference: beside the grain line's middle (its right, then its left), then
    // centred on the piece; each horizontal, then along the piece.
    for (int where = 0; where < 3; ++where)
      for (const bool along : {false, true}) {
        LabelPlacement at;
        at.size = size;
        at.turn_deg = along ? 90 : 0;
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
    // Turned along the strip, the block's middle on a point of its middle: clear of the grain
    // line where it fits so, else over it (as the label at the centroid is).
    if (slanted.empty()) slanted = slants(outline);
    for (const bool over_grain : {false, true})
      for (const Slant& slant : slanted) {
        LabelPlacement at;
        at.size = size;
        at.turn_deg = slant.turn_deg;
        at.centred = true;
        const Block b = block(text, size, true);
        at.anchor = slant.centre - (to_sheet(at, 0, 0.5 * (b.y0 + b.y1)) - at.anchor);
        if ((over_grain || !crosses(at, b, grain_a, grain_b)) && fits(outline, at, b)) {
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
