#include "garment/body_landmarks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "garment/body_facing.hpp"

namespace sd::garment {
namespace {

// One closed outline of a horizontal slice (a leg, an arm, the torso): its cut points.
struct Outline {
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double min_x = 0, max_x = 0, max_z = 0;
  double girth = 0;  // m, perimeter of the convex hull in XZ
  bool spans_centre() const { return min_x < 0 && max_x > 0; }
};

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

double hull_perimeter(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector2d> p;
  for (const Eigen::Vector3d& q : points) p.emplace_back(q.x(), q.z());
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return 0.0;
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);
  double perimeter = 0;
  for (size_t h = 0; h < hull.size(); ++h)
    perimeter += (hull[(h + 1) % hull.size()] - hull[h]).norm();
  return perimeter;
}

// The outlines of the slice y = const: cut points of the edges crossing it, grouped by the
// triangles that join them (each crossing triangle joins two cut points of one outline).
std::vector<Outline> slice(const meshing::TriMesh& mesh, double y) {
  std::map<std::pair<int, int>, int> node_of;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<int> parent;
  const auto find = [&](int a) {
    while (parent[static_cast<size_t>(a)] != a)
      a = parent[static_cast<size_t>(a)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
    return a;
  };
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    int cut[2], found = 0;
    for (int k = 0; k < 3 && found < 2; ++k) {
      int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      const double ya = mesh.vertices(a, 1) - y, yb = mesh.vertices(b, 1) - y;
      if ((ya < 0) == (yb < 0)) continue;  // both below, or both at or above
      auto [it, inserted] = node_of.try_emplace({a, b}, static_cast<int>(nodes.size()));
      if (inserted) {
        const Eigen::Vector3d pa = mesh.vertices.row(a), pb = mesh.vertices.row(b);
        nodes.push_back(pa + ya / (ya - yb) * (pb - pa));
        parent.push_back(it->second);
      }
      cut[found++] = it->second;
    }
    if (found == 2) parent[static_cast<size_t>(find(cut[0]))] = find(cut[1]);
  }
  std::map<int, Outline> by_root;
  for (size_t n = 0; n < nodes.size(); ++n)
    by_root[find(static_cast<int>(n))].points.push_back(nodes[n]);
  std::vector<Outline> outlines;
  for (auto& [root, o] : by_root) {
    if (o.points.size() < 3) continue;
    o.min_x = std::numeric_limits<double>::infinity();
    o.max_x = o.max_z = -std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : o.points) {
      o.centroid += p;
      o.min_x = std::min(o.min_x, p.x());
      o.max_x = std::max(o.max_x, p.x());
      o.max_z = std::max(o.max_z, p.z());
    }
    o.centroid /= static_cast<double>(o.points.size());
    o.girth = hull_perimeter(o.points);
    outlines.push_back(std::move(o));
  }
  return outlines;
}

const Outline* torso_of(const std::vector<Outline>& outlines) {
  const Outline* best = nullptr;
  for (const Outline& o : outlines)
    if (o.spans_centre() && (best == nullptr || o.girth > best->girth)) best = &o;
  return best;
}

// The outline beside the torso on one side (+1 left, −1 right) nearest to it: an arm.
const Outline* beside(const std::vector<Outline>& outlines, const Outline& torso, int side) {
  const Outline* best = nullptr;
  for (const Outline& o : outlines) {
    if (&o == &torso) continue;
    const double gap = side > 0 ? o.min_x - torso.max_x : torso.min_x - o.max_x;
    if (gap <= 0) continue;
    const double best_gap = best == nullptr ? 0
                            : side > 0      ? best->min_x - torso.max_x
                                            : torso.min_x - best->max_x;
    if (best == nullptr || gap < best_gap) best = &o;
  }
  return best;
}

// A point along a polyline at a fraction of its length.
Eigen::Vector3d along(const std::vector<Eigen::Vector3d>& line, double fraction) {
  double total = 0;
  for (size_t i = 1; i < line.size(); ++i) total += (line[i] - line[i - 1]).norm();
  double target = fraction * total;
  for (size_t i = 1; i < line.size(); ++i) {
    const double d = (line[i] - line[i - 1]).norm();
    if (target <= d && d > 0) return line[i - 1] + target / d * (line[i] - line[i - 1]);
    target -= d;
  }
  return line.back();
}

// The wrist on an arm's axis (shoulder first) from the girths of its outlines (girths[0], the
// shoulder's, unused). An arm with a hand: the narrowest outline past 55 % of the arm's length
// that has an outline at least 10 % wider further down (the palm) and is at least half as wide
// as the forearm (at 60 % of the length); the fingers' outlines, a fifth of it, are not wrists.
// On the Collada human (arms 45° out, hands forward) the horizontal girth falls from 0.32 m at
// y = 1.12 to 0.24 m at 1.02-1.04, widens to 0.26 m through the palm at 1.00, and splits into
// fingers of 0.04-0.06 m below 0.93. An arm without a hand (the built-in mannequin's ends in a
// rounded stump where the wrist would be: shoulder to end 0.58 m on 1.75 m, the 0.332 of the height
// that is shoulder to wrist): the last outline still 85 % as wide as the forearm (at 60 % of the
// length), where the rounded end begins. 85 %: the built-in arm's horizontal girth is 0.28 m on the
// forearm, 0.25 m at y = 0.96 and 0.23 m at 0.93, then 0.19 m at 0.90 and 0.13 m at 0.88 (the
// end is at 0.87): the stump's rounding starts between 0.93 and 0.96.
Eigen::Vector3d arm_wrist(const std::vector<Eigen::Vector3d>& axis,
                          const std::vector<double>& girths) {
  if (axis.size() < 3) return along(axis, 0.75);
  std::vector<double> arc(axis.size(), 0.0);
  for (size_t i = 1; i < axis.size(); ++i) arc[i] = arc[i - 1] + (axis[i] - axis[i - 1]).norm();
  const double length = arc.back();
  // The widest outline below each one (for the palm test).
  std::vector<double> wider_below(axis.size(), 0.0);
  for (size_t i = axis.size() - 1; i-- > 1;)
    wider_below[i] = std::max(wider_below[i + 1], girths[i + 1]);
  size_t forearm = 1;
  for (size_t i = 1; i < axis.size(); ++i)
    if (std::abs(arc[i] - 0.6 * length) < std::abs(arc[forearm] - 0.6 * length)) forearm = i;
  std::optional<size_t> narrowest;
  for (size_t i = 1; i + 1 < axis.size(); ++i)
    if (arc[i] >= 0.55 * length && girths[i] >= 0.5 * girths[forearm] &&
        wider_below[i] >= 1.1 * girths[i] && (!narrowest || girths[i] < girths[*narrowest]))
      narrowest = i;
  if (narrowest) return axis[*narrowest];
  size_t end = forearm;
  for (size_t i = forearm; i < axis.size(); ++i)
    if (girths[i] >= 0.85 * girths[forearm]) end = i;
  return axis[end];
}

}  // namespace

std::vector<SliceOutline> slice_body(const meshing::TriMesh& body, double y) {
  std::vector<SliceOutline> out;
  for (const Outline& o : slice(body, y)) {
    SliceOutline s{o.centroid, o.points.front(), o.points.front(), o.girth};
    for (const Eigen::Vector3d& p : o.points) {
      s.min = s.min.cwiseMin(p);
      s.max = s.max.cwiseMax(p);
    }
    out.push_back(s);
  }
  std::sort(out.begin(), out.end(), [](const SliceOutline& a, const SliceOutline& b) {
    return a.centroid.x() < b.centroid.x();
  });
  return out;
}

const std::vector<std::string>& landmark_names() {
  static const std::vector<std::string> names = {
      "neck_base",   "left_shoulder", "right_shoulder", "left_armpit", "right_armpit", "chest",
      "waist",       "hips",          "crotch",         "left_elbow",  "right_elbow",  "left_wrist",
      "right_wrist", "left_knee",     "right_knee",     "left_ankle",  "right_ankle"};
  return names;
}

const Landmark* BodyLandmarks::find(std::string_view name) const {
  for (const Landmark& l : points)
    if (l.name == name) return &l;
  return nullptr;
}

namespace {

// Distance from p to the polyline through `chain` (at least one point).
double polyline_distance(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& chain) {
  double best = (p - chain.front()).norm();
  for (size_t k = 0; k + 1 < chain.size(); ++k) {
    const Eigen::Vector3d d = chain[k + 1] - chain[k];
    const double t =
        d.squaredNorm() > 0 ? std::clamp((p - chain[k]).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (p - (chain[k] + t * d)).norm());
  }
  return best;
}

}  // namespace

const Landmark& BodyLandmarks::nearest(const Eigen::Vector3d& p) const {
  if (points.empty()) throw std::logic_error("BodyLandmarks::nearest: no landmarks");
  // Three corrections to the straight distance, so that a place is named by the part of the body
  // it is on: (1) an arm's joints (elbow, wrist: inside the arm, on its axis) name only places
  // within kArmReach of the arm's axis (shoulder, elbow, wrist and on over the hand): the hand
  // hangs beside the hips, and the gate named a seam on the side of the hips "near the
  // left_wrist"; (2) the torso's levels (neck base, chest, waist, hips, crotch: on the front at
  // x = 0) are measured mostly by height, half the horizontal distance counting, so that the
  // side or the back of the hips is named by the hips, not by the crotch 15 cm lower but nearer
  // through the body; (3) below. The legs' joints keep the straight distance (a flared hem beside
  // the knee is named by the knee).
  // m: the arm's radius (4-5 cm) and a hand's width of cloth hanging free: on the built-in body a
  // cape's hem beside the hand is 12-13 cm from the arm's axis, the side of the hips 17 cm.
  constexpr double kArmReach = 0.14;
  constexpr double kLevelAcross = 0.5;
  const auto find_position = [this](const std::string& name) -> std::optional<Eigen::Vector3d> {
    if (const Landmark* l = find(name)) return l->position;
    return std::nullopt;
  };
  const auto arm = [&](const std::string& name) -> std::optional<std::vector<Eigen::Vector3d>> {
    for (const std::string side : {"left_", "right_"}) {
      if (name != side + "elbow" && name != side + "wrist") continue;
      const auto shoulder = find_position(side + "shoulder");
      const auto elbow = find_position(side + "elbow");
      const auto wrist = find_position(side + "wrist");
      if (!shoulder || !elbow || !wrist) return std::nullopt;
      return std::vector<Eigen::Vector3d>{*shoulder, *elbow, *wrist,
                                          *wrist + 0.7 * (*wrist - *elbow)};  // the hand
    }
    return std::nullopt;
  };
  // (3) An arm's joints name only places farther from the body's midline than that side's
  // armpit, where the arm leaves the torso: on the built-in body the elbow is 5 cm below the
  // armpit and 6 cm out, and the back of the torso under the armpit (a kimono's underarm) was
  // "near the left_elbow".
  const auto on_torso_side_of_armpit = [&](const std::string& name, const Eigen::Vector3d& q) {
    for (const std::string side : {"left_", "right_"}) {
      if (name != side + "elbow" && name != side + "wrist") continue;
      const auto armpit = find_position(side + "armpit");
      return armpit && (armpit->x() > 0 ? q.x() : -q.x()) < std::abs(armpit->x());
    }
    return false;
  };
  const auto level = [](const std::string& name) {
    return name == "neck_base" || name == "chest" || name == "waist" || name == "hips" ||
           name == "crotch";
  };
  const Landmark* best = nullptr;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const Landmark& l : points) {
    double d = (l.position - p).norm();
    if (const auto chain = arm(l.name); chain && polyline_distance(p, *chain) > kArmReach) continue;
    if (on_torso_side_of_armpit(l.name, p)) continue;
    if (level(l.name)) {
      const Eigen::Vector3d off = p - l.position;
      d = std::hypot(off.y(), kLevelAcross * std::hypot(off.x(), off.z()));
    }
    if (d < best_distance) {
      best_distance = d;
      best = &l;
    }
  }
  if (best == nullptr)  // only arm joints, all far from the arm: the straight distance
    return *std::min_element(
        points.begin(), points.end(), [&p](const Landmark& a, const Landmark& b) {
          return (a.position - p).squaredNorm() < (b.position - p).squaredNorm();
        });
  return *best;
}

namespace {

// What a standing human figure's landmarks cannot be, with margins far outside people's range
// (standard proportions: hips ~0.53, waist ~0.63, chest ~0.72, neck base ~0.82 of the height;
// hips and chest ~15-30 % more girth than the waist): each a sentence. Trial 37's low-polygon
// man (an MDL file) had chest, waist and hips all 1.088 m round at two heights, the neck's base
// level with the armpits and the shoulders at the top of the head.
std::vector<std::string> proportion_doubts(const BodyLandmarks& l, double height) {
  std::vector<std::string> doubts;
  const double y_waist = l.find("waist")->position.y(), y_hips = l.find("hips")->position.y();
  const double y_chest = l.find("chest")->position.y(), y_neck = l.find("neck_base")->position.y();
  const double y_armpit =
      std::max(l.find("left_armpit")->position.y(), l.find("right_armpit")->position.y());
  const double y_shoulder =
      std::max(l.find("left_shoulder")->position.y(), l.find("right_shoulder")->position.y());
  if (std::max(l.chest_girth, l.hip_girth) < 1.02 * l.waist_girth)
    doubts.push_back(fmt::format(
        "the torso has no waist: chest {:.3f} m, waist {:.3f} m and hips {:.3f} m round (a "
        "person's chest and hips are 10-40 % more than the waist)",
        l.chest_girth, l.waist_girth, l.hip_girth));
  // A person's chest is at most ~1.5 times the waist round; a slice through arms held out level
  // (a T-pose) takes them in: trial 37's IQM figure read a 4.76 m chest over a 1.08 m waist.
  if (l.chest_girth > 2.0 * l.waist_girth)
    doubts.push_back(fmt::format(
        "the chest is {:.3f} m round, more than twice the waist ({:.3f} m): the arms seem held "
        "out level with it (a T-pose), and the landmarks need arms hanging apart from the torso",
        l.chest_girth, l.waist_girth));
  if (y_waist - y_hips < 0.02 * height || y_chest - y_waist < 0.02 * height)
    doubts.push_back(fmt::format(
        "hips, waist and chest were found at {:.3f}, {:.3f} and {:.3f} m, less than 2 % of the "
        "height apart",
        y_hips, y_waist, y_chest));
  if (y_neck - y_armpit < 0.02 * height)
    doubts.push_back(fmt::format("the neck's base ({:.3f} m) is level with the armpits ({:.3f} m)",
                                 y_neck, y_armpit));
  if (y_shoulder > y_neck + 0.06 * height)
    doubts.push_back(fmt::format(
        "the shoulder points ({:.3f} m) are far above the neck's base ({:.3f} m): the figure's "
        "arms may be raised, or the head taken for a shoulder",
        y_shoulder, y_neck));
  return doubts;
}

}  // namespace

namespace {

// Landmark::size of every landmark of `l` (docs/bodies.md, "Landmarks").
void set_landmark_sizes(const meshing::TriMesh& body, double height, BodyLandmarks& l) {
  const auto y_of = [&](const char* name) { return l.find(name)->position.y(); };
  for (Landmark& mark : l.points) {
    const std::string& n = mark.name;
    const bool limb =
        n.ends_with("elbow") || n.ends_with("wrist") || n.ends_with("knee") || n.ends_with("ankle");
    // A torso landmark's level: the shoulders and armpits lie where the arms join the torso,
    // whose slice is not the torso's alone; the crotch where the legs part.
    double y = mark.position.y();
    if (n.ends_with("shoulder") || n.ends_with("armpit")) y = y_of("chest");
    if (n == "crotch") y = y_of("hips");
    const std::vector<SliceOutline> outlines = slice_body(body, y);
    const SliceOutline* best = nullptr;
    double best_distance = 0.0;
    for (const SliceOutline& o : outlines) {
      // The torso: the outline across the median plane, else the nearest to it; a limb's: the
      // outline nearest the landmark.
      const bool spans = o.min.x() < 0.0 && o.max.x() > 0.0;
      const double d =
          limb ? std::hypot(o.centroid.x() - mark.position.x(), o.centroid.z() - mark.position.z())
               : (spans ? 0.0 : std::abs(o.centroid.x()));
      if (best == nullptr || d < best_distance) best = &o, best_distance = d;
    }
    if (best == nullptr) continue;  // keeps the size 1: offsets in metres
    mark.size = limb ? Eigen::Vector3d(best->girth, height, best->girth)
                     : Eigen::Vector3d(best->max.x() - best->min.x(), height,
                                       best->max.z() - best->min.z());
  }
}

}  // namespace

BodyLandmarks find_landmarks(const meshing::TriMesh& body) {
  if (body.vertex_count() == 0) throw std::runtime_error("the body has no vertices");
  const double height = body.vertices.col(1).maxCoeff();
  // Slices every 0.4 % of the height (7 mm on a 1.75 m figure), offset by a hair so that no
  // slice passes exactly through a vertex of a file with round coordinates.
  const double step = 0.004 * height;
  struct Level {
    double y;
    std::vector<Outline> outlines;
  };
  std::vector<Level> levels;
  for (double y = 0.01 * height + 1e-7 * height; y < 0.99 * height; y += step)
    levels.push_back({y, slice(body, y)});
  // A figure turned a quarter round (its arms front to back) is the likely cause when it is
  // deeper than wide: said, with what to give (trial 39, P14: the hint was in docs/bodies.md
  // only).
  const std::optional<TurnedFigure> turned = looks_turned(body);
  const auto fail = [&turned](const std::string& what) {
    throw std::runtime_error(fmt::format(
        "cannot find the body's {}: landmarks need a standing figure, feet on the floor, arms "
        "apart from the torso{}",
        what,
        turned
            ? fmt::format("; the figure looks turned: it is {:.2f} m deep (front to back) and "
                          "{:.2f} m wide, so its arms run front to back; give the way it faces "
                          "in the file (`info --facing`, `render --facing`, in a sketch \"body\": "
                          "{{\"facing\": ...}}; docs/bodies.md)",
                          turned->depth, turned->width)
            : std::string()));
  };

  // Crotch: the lowest slice above a quarter of the height whose torso outline spans x = 0.
  const Level* crotch = nullptr;
  for (const Level& l : levels)
    if (l.y > 0.25 * height && torso_of(l.outlines) != nullptr) {
      crotch = &l;
      break;
    }
  if (crotch == nullptr) fail("crotch (where the legs join)");
  // Armpits: the highest slice below 85 % of the height with an arm beside the torso.
  std::array<const Level*, 2> armpit_level{nullptr, nullptr};
  std::array<Eigen::Vector3d, 2> armpit;
  for (int s = 0; s < 2; ++s) {
    const int side = s == 0 ? 1 : -1;
    for (const Level& l : levels) {
      if (l.y <= crotch->y || l.y > 0.85 * height) continue;
      const Outline* torso = torso_of(l.outlines);
      if (torso == nullptr) continue;
      const Outline* arm = beside(l.outlines, *torso, side);
      if (arm == nullptr) continue;
      armpit_level[static_cast<size_t>(s)] = &l;
      const double x =
          side > 0 ? 0.5 * (torso->max_x + arm->min_x) : 0.5 * (torso->min_x + arm->max_x);
      armpit[static_cast<size_t>(s)] = {x, l.y + 0.5 * step, torso->centroid.z()};
    }
    if (armpit_level[static_cast<size_t>(s)] == nullptr)
      fail(s == 0 ? "left armpit" : "right armpit");
  }
  const double top_of_armpits = std::max(armpit[0].y(), armpit[1].y());

  // Torso girths: waist the narrowest between the hips and the chest, hips the widest below
  // the waist, chest the widest between the waist and the armpits.
  const auto torso_at = [&](const Level& l) { return torso_of(l.outlines); };
  const auto extreme = [&](double from, double to, bool widest) -> const Level* {
    const Level* best = nullptr;
    double value = 0;
    for (const Level& l : levels) {
      if (l.y < from || l.y > to) continue;
      const Outline* t = torso_at(l);
      if (t == nullptr) continue;
      if (best == nullptr || (widest ? t->girth > value : t->girth < value))
        best = &l, value = t->girth;
    }
    return best;
  };
  const double torso_span = top_of_armpits - crotch->y;
  const Level* waist =
      extreme(crotch->y + 0.3 * torso_span, top_of_armpits - 0.2 * torso_span, false);
  if (waist == nullptr) fail("waist");
  const Level* hips = extreme(crotch->y + 0.1 * torso_span, waist->y, true);
  const Level* chest = extreme(waist->y, top_of_armpits - 0.03 * torso_span, true);
  if (hips == nullptr || chest == nullptr) fail("hips or chest");
  const auto front = [&](const Level& l) {
    const Outline& t = *torso_at(l);
    return Eigen::Vector3d(0.0, l.y, t.max_z);
  };

  // Neck: the narrowest torso outline between the armpits and 95 % of the height; its base the
  // lowest slice above the armpits no wider than 1.3 times that.
  const Level* narrowest = nullptr;
  for (const Level& l : levels)
    if (l.y > top_of_armpits && l.y < 0.95 * height && torso_at(l) != nullptr &&
        (narrowest == nullptr || torso_at(l)->girth < torso_at(*narrowest)->girth))
      narrowest = &l;
  if (narrowest == nullptr) fail("neck");
  const Level* neck_base = narrowest;
  for (const Level& l : levels)
    if (l.y > top_of_armpits && l.y < narrowest->y && torso_at(l) != nullptr &&
        torso_at(l)->girth < 1.3 * torso_at(*narrowest)->girth) {
      neck_base = &l;
      break;
    }

  BodyLandmarks out;
  out.points.push_back({"neck_base", front(*neck_base)});
  // Shoulder points: the top of the body straight above each armpit.
  std::array<Eigen::Vector3d, 2> shoulder;
  for (int s = 0; s < 2; ++s) {
    const Eigen::Vector3d a = armpit[static_cast<size_t>(s)];
    double top = a.y();
    for (const Level& l : levels)
      for (const Outline& o : l.outlines)
        if (l.y > a.y() && o.min_x <= a.x() && o.max_x >= a.x()) top = std::max(top, l.y);
    shoulder[static_cast<size_t>(s)] = {a.x(), top, a.z()};
  }
  out.points.push_back({"left_shoulder", shoulder[0]});
  out.points.push_back({"right_shoulder", shoulder[1]});
  out.points.push_back({"left_armpit", armpit[0]});
  out.points.push_back({"right_armpit", armpit[1]});
  out.points.push_back({"chest", front(*chest)});
  out.points.push_back({"waist", front(*waist)});
  out.points.push_back({"hips", front(*hips)});
  out.points.push_back({"crotch", {0.0, crotch->y - 0.5 * step, torso_at(*crotch)->centroid.z()}});
  out.chest_girth = torso_at(*chest)->girth;
  out.waist_girth = torso_at(*waist)->girth;
  out.hip_girth = torso_at(*hips)->girth;

  // Arm axis: the shoulder point, then the centres of the arm outlines going down (following
  // the outline nearest the last centre), to the lowest slice of the arm. The elbow at 42 % of
  // its length (shoulder to elbow 0.186, elbow to wrist 0.146, hand 0.108 of the height in
  // standard body-segment proportions). The wrist from the arm's shape (arm_wrist below): a
  // proportion of the length put it 13 cm above the end of the built-in mannequin's arm, which
  // has no hand, and a long sleeve ended there came out three-quarter length.
  std::array<Eigen::Vector3d, 2> elbow, wrist;
  for (int s = 0; s < 2; ++s) {
    std::vector<Eigen::Vector3d> axis = {shoulder[static_cast<size_t>(s)]};
    std::vector<double> girths = {0.0};  // of each axis point's outline (none at the shoulder)
    Eigen::Vector3d last = armpit[static_cast<size_t>(s)];
    for (auto l = levels.rbegin(); l != levels.rend(); ++l) {
      if (l->y >= armpit[static_cast<size_t>(s)].y()) continue;
      const Outline* torso = torso_at(*l);
      const Outline* next = nullptr;
      for (const Outline& o : l->outlines) {
        if (&o == torso) continue;
        if ((o.centroid - last).head<1>().norm() > 0.06 * height) continue;  // not this arm
        if (std::abs(o.centroid.y() - last.y()) > 4 * step) continue;
        if (next == nullptr || (o.centroid - last).norm() < (next->centroid - last).norm())
          next = &o;
      }
      if (next == nullptr) {
        if (axis.size() > 1) break;  // the arm ended
        continue;
      }
      last = next->centroid;
      axis.push_back(last);
      girths.push_back(next->girth);
    }
    elbow[static_cast<size_t>(s)] = along(axis, 0.42);
    wrist[static_cast<size_t>(s)] = arm_wrist(axis, girths);
  }
  out.points.push_back({"left_elbow", elbow[0]});
  out.points.push_back({"right_elbow", elbow[1]});
  out.points.push_back({"left_wrist", wrist[0]});
  out.points.push_back({"right_wrist", wrist[1]});

  // Knees and ankles: centres of the leg outlines at 0.59 and 0.08 of the crotch height (knee
  // 0.285 and ankle 0.039 of the height against a crotch at 0.485, standard proportions).
  for (const auto& [name, fraction] : {std::pair{"knee", 0.59}, std::pair{"ankle", 0.08}}) {
    const double y = fraction * crotch->y;
    const Level& l = *std::min_element(
        levels.begin(), levels.end(),
        [y](const Level& a, const Level& b) { return std::abs(a.y - y) < std::abs(b.y - y); });
    for (int s = 0; s < 2; ++s) {
      const int side = s == 0 ? 1 : -1;
      const Outline* leg = nullptr;
      for (const Outline& o : l.outlines)
        if (o.centroid.x() * side > 0 && (leg == nullptr || o.girth > leg->girth)) leg = &o;
      if (leg == nullptr) fail(fmt::format("{} {}", s == 0 ? "left" : "right", name));
      out.points.push_back({fmt::format("{}_{}", s == 0 ? "left" : "right", name), leg->centroid});
    }
  }
  // Keep the documented order.
  std::vector<Landmark> ordered;
  for (const std::string& name : landmark_names()) ordered.push_back(*out.find(name));
  out.points = std::move(ordered);
  out.height = height;
  set_landmark_sizes(body, height, out);
  out.doubts = proportion_doubts(out, height);
  return out;
}

Eigen::Vector3d landmark_point_for(const BodyLandmarks& body, const BodyLandmarks& drawn,
                                   const Landmark& l, const Eigen::Vector3d& offset) {
  const Landmark* d = drawn.find(l.name);
  if (d == nullptr) return l.position + offset;
  Eigen::Vector3d p = l.position + offset.cwiseProduct(l.size).cwiseQuotient(d->size);
  // The mirror plane stays the mirror plane: a point the offset puts on x = 0 of the body it was
  // written for (within kOnPlaneRounding) lands on x = 0 here. Scaled by the torso's width, a
  // centre-back point written from the left armpit landed a few millimetres off the plane, and
  // its curve was no longer its own mirror (trial 43, P5).
  if (std::abs(d->position.x() + offset.x()) <= kOnPlaneRounding) p.x() = 0;
  if (l.name.ends_with("elbow") || l.name.ends_with("wrist")) return p;
  // The levels of both bodies, from the feet up (each rises on both: find_landmarks orders them).
  std::vector<double> from = {0.0}, to = {0.0};
  for (const char* name : {"left_ankle", "left_knee", "crotch", "hips", "waist", "chest",
                           "left_armpit", "left_shoulder", "neck_base"}) {
    const Landmark* a = drawn.find(name);
    const Landmark* b = body.find(name);
    if (a == nullptr || b == nullptr) return p;
    from.push_back(a->position.y());
    to.push_back(b->position.y());
  }
  from.push_back(drawn.height);
  to.push_back(body.height);
  for (size_t i = 1; i < from.size(); ++i)
    if (!(from[i] > from[i - 1]) || !(to[i] > to[i - 1])) return p;  // a level out of order
  const double y = d->position.y() + offset.y();
  // Beyond the feet or the top, the nearest segment's scale.
  size_t i = 1;
  while (i + 1 < from.size() && y > from[i]) ++i;
  p.y() = to[i - 1] + (y - from[i - 1]) * (to[i] - to[i - 1]) / (from[i] - from[i - 1]);
  return p;
}

}  // namespace sd::garment
