#include "garment/sketch_file.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "garment/body_landmarks.hpp"
#include "garment/input_checks.hpp"
#include "garment/sketch_inputs.hpp"
#include "garment/sketch_ranges.hpp"

namespace sd::garment {
namespace {

using nlohmann::json;

// Levenshtein distance, for "did you mean" hints on misspelt keys and names.
size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string type_name(const json& value) {
  if (value.is_string()) return fmt::format("the text \"{}\"", value.get<std::string>());
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number()) return fmt::format("the number {}", value.dump());
  if (value.is_null()) return "null";
  if (value.is_array()) return "a list";
  return "an object";
}

// JSON has no NaN or infinity literal, but a number like 1e999 overflows a double; the JSON
// library rejects it without saying where. Such literals are replaced by a marked string before
// parsing, so the reader reports them with their JSON path.
constexpr const char* kOverflowMarker = "\x01sketchdrape-overflow:";

std::string mark_overflowing_numbers(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '"') {  // copy a string literal with its escapes
      size_t j = i + 1;
      while (j < text.size() && text[j] != '"') j += text[j] == '\\' ? 2 : 1;
      j = std::min(j + 1, text.size());
      out.append(text.substr(i, j - i));
      i = j;
    } else if (c == '/' && i + 1 < text.size() && (text[i + 1] == '/' || text[i + 1] == '*')) {
      const bool line = text[i + 1] == '/';
      size_t j = line ? text.find('\n', i) : text.find("*/", i + 2);
      j = j == std::string_view::npos ? text.size() : j + (line ? 0 : 2);
      out.append(text.substr(i, j - i));
      i = j;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      size_t j = i + 1;
      while (j < text.size() &&
             (std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '.' ||
              text[j] == 'e' || text[j] == 'E' || text[j] == '+' || text[j] == '-'))
        ++j;
      const std::string token(text.substr(i, j - i));
      const double value = std::strtod(token.c_str(), nullptr);
      if (std::isinf(value))
        out +=
            fmt::format("\"\\u0001sketchdrape-overflow:{}\"", token);  // JSON escape of the marker
      else
        out += token;
      i = j;
    } else {
      out += c;
      ++i;
    }
  }
  return out;
}

// Reads one JSON document with the context needed for messages.
class Reader {
 public:
  explicit Reader(const Sketch& sketch) : sketch_(sketch) {}

  [[noreturn]] void fail(const std::string& path, const std::string& sentence) const {
    sketch_.fail(path, sentence);
  }

  // Rejects keys not in `known`, suggesting the nearest known one.
  void check_keys(const json& object, const std::string& path,
                  std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : object.items()) {
      if (std::find(known.begin(), known.end(), key) != known.end()) continue;
      std::string_view best;
      size_t best_distance = 3;  // suggest only close spellings
      for (std::string_view k : known) {
        const size_t d = edit_distance(key, k);
        if (d < best_distance) best = k, best_distance = d;
      }
      std::string sentence = fmt::format("unknown key '{}'", key);
      if (!best.empty())
        sentence += fmt::format(" (did you mean '{}'?)", best);
      else
        sentence += fmt::format(" (known keys here: {})", fmt::join(known, ", "));
      fail(path + "/" + key, sentence);
    }
  }

  void require_object(const json& value, const std::string& path, std::string_view what) const {
    if (!value.is_object())
      fail(path, fmt::format("{} must be an object {{...}}, not {}", what, type_name(value)));
  }

  double number(const json& value, const std::string& path) const {
    if (value.is_string() && value.get<std::string>().starts_with(kOverflowMarker)) {
      fail(path,
           fmt::format("the number {} is not finite (too large for a double); coordinates "
                       "and sizes must be finite numbers",
                       value.get<std::string>().substr(std::string_view(kOverflowMarker).size())));
    }
    if (value.is_string()) {
      fail(path, fmt::format("expected a number, got {}; JSON numbers are written without quotes "
                             "and must be finite (no NaN or infinity)",
                             type_name(value)));
    }
    if (!value.is_number()) fail(path, fmt::format("expected a number, got {}", type_name(value)));
    const double x = value.get<double>();
    if (!std::isfinite(x))
      fail(path, fmt::format("the number {} is not finite; coordinates and sizes must be finite "
                             "numbers",
                             value.dump()));
    return x;
  }

  double positive(const json& value, const std::string& path) const {
    const double x = number(value, path);
    if (!(x > 0)) fail(path, fmt::format("must be greater than zero, not {}", x));
    return x;
  }

  double non_negative(const json& value, const std::string& path) const {
    const double x = number(value, path);
    if (x < 0) fail(path, fmt::format("must not be negative, not {}", x));
    return x;
  }

  int integer(const json& value, const std::string& path, int min_value) const {
    const double x = number(value, path);
    if (x != std::floor(x) || x < min_value || x > 1e7)
      fail(path,
           fmt::format("expected a whole number of at least {}, got {}", min_value, value.dump()));
    return static_cast<int>(x);
  }

  bool boolean(const json& value, const std::string& path) const {
    if (!value.is_boolean())
      fail(path, fmt::format("expected true or false, got {}", type_name(value)));
    return value.get<bool>();
  }

  std::string text(const json& value, const std::string& path) const {
    if (!value.is_string())
      fail(path, fmt::format("expected text in quotes, got {}", type_name(value)));
    return value.get<std::string>();
  }

  std::string identifier(const json& value, const std::string& path) const {
    std::string id = text(value, path);
    if (id.empty()) fail(path, "an id must not be empty");
    const bool ok = std::all_of(id.begin(), id.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!ok) fail(path, fmt::format("id '{}' may only use letters, digits, '_' and '-'", id));
    return id;
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vector(const json& value, const std::string& path) const {
    if (!value.is_array() || value.size() != N)
      fail(path,
           fmt::format(
               "expected a point of {} numbers [{}], got {}", N, N == 2 ? "x, y" : "x, y, z",
               value.is_array() ? fmt::format("{} numbers", value.size()) : type_name(value)));
    Eigen::Matrix<double, N, 1> v;
    for (int k = 0; k < N; ++k) v[k] = number(value[k], fmt::format("{}/{}", path, k));
    return v;
  }

  // A point in the world or in a view plane: within ±kMaxCoordinate metres on every axis.
  template <int N>
  Eigen::Matrix<double, N, 1> position(const json& value, const std::string& path) const {
    const Eigen::Matrix<double, N, 1> v = vector<N>(value, path);
    for (int k = 0; k < N; ++k)
      if (std::abs(v[k]) > kMaxCoordinate)
        fail(fmt::format("{}/{}", path, k),
             out_of_range_sentence(v[k], -kMaxCoordinate, kMaxCoordinate, "the coordinate"));
    return v;
  }

  // An edge length in metres: 2 mm .. 50 cm.
  double edge_length(const json& value, const std::string& path) const {
    const double x = positive(value, path);
    if (x < 0.002 || x > 0.5) fail(path, out_of_range_sentence(x, 0.002, 0.5, "an edge length of"));
    return x;
  }

  // A list of at most `most` entries at `path`.
  void check_count(const json& list, const std::string& path, size_t most,
                   std::string_view what) const {
    if (list.is_array() && list.size() > most)
      fail(path, fmt::format("{} {} is more than the {} allowed", list.size(), what, most));
  }

  ViewSpec view(const json& value, const std::string& path) const {
    ViewSpec view;
    if (value.is_string()) {
      const std::string name = value.get<std::string>();
      static const std::pair<const char*, ViewKind> kNames[] = {{"front", ViewKind::kFront},
                                                                {"back", ViewKind::kBack},
                                                                {"left", ViewKind::kLeft},
                                                                {"right", ViewKind::kRight}};
      for (const auto& [n, kind] : kNames)
        if (name == n) {
          view.kind = kind;
          return view;
        }
      fail(path, fmt::format("there is no view called '{}'; use front, back, left, right or "
                             "{{\"camera\": {{\"eye\": [...], \"target\": [...]}}}}",
                             name));
    }
    if (!value.is_object())
      fail(path, fmt::format("a view is a name (front, back, left, right) or a camera object, "
                             "not {}",
                             type_name(value)));
    check_keys(value, path, {"camera"});
    if (!value.contains("camera")) fail(path, "a view object needs a \"camera\"");
    const json& cam = value["camera"];
    const std::string cpath = path + "/camera";
    require_object(cam, cpath, "a camera");
    check_keys(cam, cpath, {"eye", "target", "up", "fov"});
    view.kind = ViewKind::kCamera;
    if (!cam.contains("eye")) fail(cpath, "a camera needs an \"eye\" point [x, y, z]");
    view.camera.eye = position<3>(cam["eye"], cpath + "/eye");
    if (cam.contains("target")) view.camera.target = position<3>(cam["target"], cpath + "/target");
    if (cam.contains("up")) view.camera.up = vector<3>(cam["up"], cpath + "/up");
    if (cam.contains("fov")) {
      view.camera.fov_degrees = positive(cam["fov"], cpath + "/fov");
      if (view.camera.fov_degrees >= 170)
        fail(cpath + "/fov", "the field of view must be below 170 degrees");
    }
    const Eigen::Vector3d dir = view.camera.target - view.camera.eye;
    if (dir.norm() < 1e-6) fail(cpath, "the camera's eye and target are the same point");
    if (dir.normalized().cross(view.camera.up).norm() < 1e-3)
      fail(cpath + "/up", "the camera's up direction is parallel to its viewing direction");
    return view;
  }

 private:
  const Sketch& sketch_;
};

// "poses": [{"time": 0.5, "mesh": "raised.obj"}, ...] of a "poses" motion.
void parse_body_poses(const Reader& r, const json& m, const std::string& mpath,
                      const BodySpec& body, BodyMotionSpec& motion) {
  if (!m.contains("poses"))
    r.fail(mpath,
           "a \"poses\" motion needs \"poses\": [{\"time\": 1.0, \"mesh\": "
           "\"pose.obj\"}, ...], the body's mesh in other poses");
  const json& list = m["poses"];
  const std::string lpath = mpath + "/poses";
  if (!list.is_array() || list.empty())
    r.fail(lpath, "expected a list of at least one pose {\"time\": seconds, \"mesh\": file}");
  if (body.mesh == "builtin")
    r.fail(lpath,
           "the poses must be meshes of the same body: give the body's own file as "
           "\"mesh\" (the pose at time 0) instead of \"builtin\"");
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string ppath = lpath + "/" + std::to_string(k);
    const json& p = list[k];
    r.require_object(p, ppath, "a pose");
    r.check_keys(p, ppath, {"time", "mesh"});
    if (!p.contains("time") || !p.contains("mesh"))
      r.fail(ppath,
             "a pose needs a \"time\" (seconds) and a \"mesh\" (the body file in that pose)");
    BodyPoseSpec pose;
    pose.json_path = ppath;
    pose.time = r.positive(p["time"], ppath + "/time");
    pose.mesh = r.text(p["mesh"], ppath + "/mesh");
    if (pose.mesh.empty()) r.fail(ppath + "/mesh", "the pose's mesh path is empty");
    if (!motion.poses.empty() && !(pose.time > motion.poses.back().time))
      r.fail(ppath + "/time",
             fmt::format("the poses must come in time order: {} s is not after {} s", pose.time,
                         motion.poses.back().time));
    motion.poses.push_back(pose);
  }
}

void parse_body(const Reader& r, const json& j, BodySpec& body) {
  const std::string path = "/body";
  if (j.is_string()) {  // shorthand: "body": "builtin"
    body.mesh = r.text(j, path);
    return;
  }
  r.require_object(j, path, "body");
  r.check_keys(j, path, {"mesh", "height", "up", "scale", "motion"});
  if (j.contains("mesh")) body.mesh = r.text(j["mesh"], path + "/mesh");
  if (body.mesh.empty()) r.fail(path + "/mesh", "the body mesh path is empty");
  if (j.contains("height")) {
    body.height = r.positive(j["height"], path + "/height");
    if (*body.height < kMinBodyHeight || *body.height > kMaxBodyHeight)
      r.fail(path + "/height", out_of_range_sentence(*body.height, kMinBodyHeight, kMaxBodyHeight,
                                                     "a body height of"));
  }
  if (j.contains("scale")) body.scale = r.positive(j["scale"], path + "/scale");
  if (j.contains("up")) {
    const std::string up = r.text(j["up"], path + "/up");
    static const std::set<std::string> kAxes = {"x", "y", "z", "+x", "+y", "+z", "-x", "-y", "-z",
                                                "X", "Y", "Z", "+X", "+Y", "+Z", "-X", "-Y", "-Z"};
    if (!kAxes.contains(up))
      r.fail(path + "/up", fmt::format("'{}' is not an axis; use +x, -x, +y, -y, +z or -z", up));
    body.up = up;
  }
  if (j.contains("motion")) {
    const std::string mpath = path + "/motion";
    const json& m = j["motion"];
    r.require_object(m, mpath, "the body's motion");
    if (body.mesh == "none") r.fail(mpath, "a body motion needs a body: \"mesh\" is \"none\"");
    BodyMotionSpec motion;
    if (m.contains("type")) motion.type = r.text(m["type"], mpath + "/type");
    if (motion.type == "poses") {
      r.check_keys(m, mpath, {"type", "poses"});
      parse_body_poses(r, m, mpath, body, motion);
      body.motion = motion;
      return;
    }
    if (motion.type != "arms-lowering")
      r.fail(mpath + "/type",
             fmt::format("'{}' is not a body motion; use arms-lowering or poses", motion.type));
    r.check_keys(m, mpath, {"type", "degrees", "start", "duration"});
    if (m.contains("degrees")) motion.degrees = r.number(m["degrees"], mpath + "/degrees");
    // The built-in mannequin's arms hang 17° out from the body: lowering them by more than 15°
    // would press them into the torso.
    if (motion.degrees < -30.0 || motion.degrees > 15.0)
      r.fail(mpath + "/degrees",
             fmt::format("{}° is too far: the arms can be lowered by up to 15° (into the torso "
                         "beyond) and raised by up to 30° (negative degrees)",
                         motion.degrees));
    if (m.contains("start")) motion.start = r.non_negative(m["start"], mpath + "/start");
    if (m.contains("duration")) motion.duration = r.positive(m["duration"], mpath + "/duration");
    body.motion = motion;
  }
}

// The landmarks of the sketch's body (docs/bodies.md), found once per body and kept: a sketch
// that places points relative to them loads its body while it is read.
const BodyLandmarks& sketch_landmarks(const Reader& r, const Sketch& sk, const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, BodyLandmarks> cache;
  const std::string key =
      fmt::format("{}|{}|{}|{}", sk.resolve(sk.body.mesh).string(), sk.body.height.value_or(0),
                  sk.body.scale.value_or(0), sk.body.up.value_or(""));
  const std::lock_guard lock(mutex);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  const Body body = load_sketch_body(sk);
  try {
    return cache.emplace(key, find_landmarks(body.mesh)).first->second;
  } catch (const std::runtime_error& e) {
    r.fail(path, fmt::format("a point is given relative to a landmark, but the body has none: {}",
                             e.what()));
  }
}

// {"at": "left_armpit", "offset": [dx, dy, dz]}: a landmark's position plus an offset (m).
Eigen::Vector3d landmark_point(const Reader& r, const json& j, const std::string& path,
                               const Sketch& sk) {
  r.check_keys(j, path, {"at", "offset"});
  if (!j.contains("at"))
    r.fail(path,
           "a point given by a landmark needs \"at\": its name, e.g. {\"at\": "
           "\"left_armpit\", \"offset\": [0.01, -0.03, 0]}");
  const std::string name = r.text(j["at"], path + "/at");
  const Eigen::Vector3d offset =
      j.contains("offset") ? r.vector<3>(j["offset"], path + "/offset") : Eigen::Vector3d::Zero();
  const BodyLandmarks& landmarks = sketch_landmarks(r, sk, path);
  if (const Landmark* l = landmarks.find(name)) return l->position + offset;
  std::string names;
  for (const std::string& n : landmark_names()) names += (names.empty() ? "" : ", ") + n;
  r.fail(path + "/at", fmt::format("there is no landmark '{}'; the landmarks are {}", name, names));
}

CurveSpec parse_curve(const Reader& r, const json& j, const std::string& path, const Sketch& sk) {
  r.require_object(j, path, "a curve");
  r.check_keys(j, path,
               {"id", "view", "points", "points3d", "offset", "on_body", "smooth", "closed",
                "edge_length", "edges"});
  CurveSpec curve;
  curve.json_path = path;
  if (!j.contains("id")) r.fail(path, "every curve needs an \"id\"");
  curve.id = r.identifier(j["id"], path + "/id");
  const bool has_2d = j.contains("points"), has_3d = j.contains("points3d");
  if (has_2d == has_3d)
    r.fail(path, fmt::format("curve '{}' needs exactly one of \"points\" (2D, drawn in a view) or "
                             "\"points3d\"",
                             curve.id));
  const std::string key = has_2d ? "points" : "points3d";
  const json& pts = j[key];
  const std::string ppath = path + "/" + key;
  if (!pts.is_array())
    r.fail(ppath, fmt::format("expected a list of points, got {}", type_name(pts)));
  if (pts.size() < 2) r.fail(ppath, fmt::format("curve '{}' needs at least 2 points", curve.id));
  r.check_count(pts, ppath, kMaxPointsPerCurve, "points");
  for (size_t i = 0; i < pts.size(); ++i) {
    const std::string ip = fmt::format("{}/{}", ppath, i);
    if (has_2d)
      curve.points.push_back(r.position<2>(pts[i], ip));
    else
      curve.points3d.push_back(pts[i].is_object() ? landmark_point(r, pts[i], ip, sk)
                                                  : r.position<3>(pts[i], ip));
  }
  if (j.contains("view")) {
    if (has_3d)
      r.fail(path + "/view",
             "a \"view\" only applies to 2D \"points\"; \"points3d\" are world "
             "coordinates");
    curve.view = r.view(j["view"], path + "/view");
  }
  curve.offset = j.contains("offset") ? r.number(j["offset"], path + "/offset") : sk.offset;
  if (std::abs(curve.offset) > 0.5)
    r.fail(path + "/offset", fmt::format("an offset of {} m is more than half a metre from the "
                                         "body; offsets are in metres (1 cm = 0.01)",
                                         curve.offset));
  if (j.contains("on_body")) curve.on_body = r.boolean(j["on_body"], path + "/on_body");
  if (j.contains("smooth")) curve.smooth = r.boolean(j["smooth"], path + "/smooth");
  if (j.contains("closed")) curve.closed = r.boolean(j["closed"], path + "/closed");
  if (curve.closed && pts.size() < 3)
    r.fail(ppath, fmt::format("closed curve '{}' needs at least 3 points", curve.id));
  if (j.contains("edge_length"))
    curve.edge_length = r.edge_length(j["edge_length"], path + "/edge_length");
  if (j.contains("edges")) {
    curve.edges = r.integer(j["edges"], path + "/edges", 1);
    if (*curve.edges > kMaxCurveEdges)
      r.fail(path + "/edges", fmt::format("{} edges on one curve is more than the {} allowed",
                                          *curve.edges, kMaxCurveEdges));
  }
  // Repeated consecutive points make a stroke without direction there.
  const size_t n = has_2d ? curve.points.size() : curve.points3d.size();
  for (size_t i = 1; i < n; ++i) {
    const double d = has_2d ? (curve.points[i] - curve.points[i - 1]).norm()
                            : (curve.points3d[i] - curve.points3d[i - 1]).norm();
    if (d < 1e-6)
      r.fail(fmt::format("{}/{}", ppath, i),
             fmt::format("point {} of curve '{}' repeats the point before it", i, curve.id));
  }
  return curve;
}

PanelSpec parse_panel(const Reader& r, const json& j, const std::string& path, const Sketch& sk) {
  r.require_object(j, path, "a panel");
  r.check_keys(j, path,
               {"id", "boundary", "corners", "fabric", "mirror", "edge_length", "ease", "seed",
                "rest", "seam_allowance", "fit"});
  PanelSpec panel;
  panel.json_path = path;
  if (!j.contains("id")) r.fail(path, "every panel needs an \"id\"");
  panel.id = r.identifier(j["id"], path + "/id");
  if (!j.contains("boundary"))
    r.fail(path, fmt::format("panel '{}' needs a \"boundary\": its curve ids in order, or "
                             "\"auto\"",
                             panel.id));
  const json& b = j["boundary"];
  if (b.is_string()) {
    if (b.get<std::string>() != "auto")
      r.fail(path + "/boundary", fmt::format("\"boundary\" is a list of curve ids or \"auto\", "
                                             "not \"{}\"",
                                             b.get<std::string>()));
    panel.auto_boundary = true;
    if (!j.contains("seed"))
      r.fail(path + "/boundary",
             fmt::format("panel '{}' has \"boundary\": \"auto\" but no \"seed\": say which "
                         "region of the curves it is with a point inside it, e.g. \"seed\": "
                         "{{\"view\": \"front\", \"point\": [0.1, 1.0]}}",
                         panel.id));
  } else {
    if (!b.is_array())
      r.fail(path + "/boundary", fmt::format("expected a list of curve ids, got {}", type_name(b)));
    if (b.empty())
      r.fail(path + "/boundary", fmt::format("panel '{}' has no boundary curves", panel.id));
    for (size_t i = 0; i < b.size(); ++i) {
      const std::string ip = fmt::format("{}/boundary/{}", path, i);
      std::string id = r.text(b[i], ip);
      const std::string base = id.ends_with(".mirror") ? id.substr(0, id.size() - 7) : id;
      if (sk.find_curve(base) == nullptr) {
        std::string sentence = fmt::format("curve '{}' is not defined", id);
        size_t best = 3;
        std::string hint;
        for (const CurveSpec& c : sk.curves) {
          const size_t d = edit_distance(base, c.id);
          if (d < best) best = d, hint = c.id;
        }
        if (!hint.empty()) sentence += fmt::format(" (did you mean '{}'?)", hint);
        r.fail(ip, sentence);
      }
      panel.boundary.push_back(std::move(id));
    }
  }
  if (j.contains("seed")) {
    const std::string sp = path + "/seed";
    if (!panel.auto_boundary)
      r.fail(sp,
             "a \"seed\" only picks the region of a \"boundary\": \"auto\" panel; this "
             "panel lists its curves");
    const json& sj = j["seed"];
    r.require_object(sj, sp, "a seed");
    r.check_keys(sj, sp, {"view", "point", "point3d"});
    SeedSpec seed;
    seed.json_path = sp;
    if (sj.contains("point") == sj.contains("point3d"))
      r.fail(sp,
             "a seed needs exactly one of \"point\" ([x, y] in its \"view\") or "
             "\"point3d\" ([x, y, z])");
    if (sj.contains("point")) seed.point = r.position<2>(sj["point"], sp + "/point");
    if (sj.contains("point3d")) seed.point3d = r.position<3>(sj["point3d"], sp + "/point3d");
    if (sj.contains("view")) {
      if (seed.point3d)
        r.fail(sp + "/view",
               "a \"view\" only applies to a 2D \"point\"; \"point3d\" is in "
               "world coordinates");
      seed.view = r.view(sj["view"], sp + "/view");
    }
    panel.seed = seed;
  }
  if (j.contains("corners")) {
    if (panel.auto_boundary)
      r.fail(path + "/corners", "explicit corners need an explicit boundary list");
    const json& c = j["corners"];
    if (!c.is_array()) r.fail(path + "/corners", "expected a list of curve ids");
    for (size_t i = 0; i < c.size(); ++i) {
      const std::string ip = fmt::format("{}/corners/{}", path, i);
      std::string id = r.text(c[i], ip);
      if (std::find(panel.boundary.begin(), panel.boundary.end(), id) == panel.boundary.end())
        r.fail(ip, fmt::format("corner '{}' is not one of panel '{}''s boundary curves (a corner "
                               "is named by the curve that starts there)",
                               id, panel.id));
      panel.corners.push_back(std::move(id));
    }
  }
  panel.fabric = j.contains("fabric") ? r.text(j["fabric"], path + "/fabric") : sk.fabric;
  if (j.contains("mirror")) panel.mirror = r.boolean(j["mirror"], path + "/mirror");
  if (j.contains("edge_length"))
    panel.edge_length = r.edge_length(j["edge_length"], path + "/edge_length");
  if (j.contains("ease")) {
    panel.ease = r.positive(j["ease"], path + "/ease");
    if (panel.ease < 0.5 || panel.ease > 2.0)
      r.fail(path + "/ease", fmt::format("ease {} is outside 0.5 .. 2 (1 = rest shape as "
                                         "designed, 1.05 = 5% looser)",
                                         panel.ease));
  }
  if (j.contains("rest")) {
    panel.rest = r.text(j["rest"], path + "/rest");
    if (*panel.rest != "flat" && *panel.rest != "shaped")
      r.fail(path + "/rest", fmt::format("unknown rest shape '{}'; use \"flat\" (the flattened "
                                         "pattern piece) or \"shaped\" (as drawn on the body)",
                                         *panel.rest));
  }
  if (j.contains("seam_allowance")) {
    panel.seam_allowance = r.number(j["seam_allowance"], path + "/seam_allowance");
    if (*panel.seam_allowance < 0 || *panel.seam_allowance > 0.1)
      r.fail(path + "/seam_allowance",
             fmt::format("seam allowance {} m is outside 0 .. 0.1 m", *panel.seam_allowance));
  }
  if (j.contains("fit")) {
    const std::string fit = r.text(j["fit"], path + "/fit");
    if (fit == "auto")
      panel.fit = PanelFit::kAuto;
    else if (fit == "body")
      panel.fit = PanelFit::kBody;
    else if (fit == "free")
      panel.fit = PanelFit::kFree;
    else
      r.fail(path + "/fit", fmt::format("\"fit\" is \"auto\", \"body\" (the panel lies on the "
                                        "body) or \"free\" (spanned by its curves, pushed out of "
                                        "the body only where it would be inside), not \"{}\"",
                                        fit));
  }
  return panel;
}

// "adaptive": true | false | {"enabled": ..., "refine_threshold": ..., ...}.
void parse_adaptive(const Reader& r, const json& a, SimulateSpec& sim) {
  const std::string path = "/simulate/adaptive";
  sim.adaptive_given = true;
  if (a.is_boolean()) {
    sim.adaptive = a.get<bool>();
    return;
  }
  if (!a.is_object())
    r.fail(path,
           "expected true, false or an object of adaptive settings {\"refine_threshold\": "
           "0.002, ...}");
  r.check_keys(a, path,
               {"enabled", "refine_threshold", "coarsen_threshold", "steady_rate", "min_lifetime",
                "min_level", "max_level", "max_vertices", "merge_batch", "even_levels"});
  AdaptiveSpec& s = sim.adaptive_settings;
  if (a.contains("enabled")) sim.adaptive = r.boolean(a["enabled"], path + "/enabled");
  if (a.contains("refine_threshold"))
    s.refine_threshold = r.positive(a["refine_threshold"], path + "/refine_threshold");
  if (a.contains("coarsen_threshold"))
    s.coarsen_threshold = r.positive(a["coarsen_threshold"], path + "/coarsen_threshold");
  if (s.refine_threshold && s.coarsen_threshold && !(*s.coarsen_threshold < *s.refine_threshold))
    r.fail(path + "/coarsen_threshold",
           fmt::format("the coarsen threshold ({} m) must be below the refine threshold ({} m): "
                       "the gap keeps a merged block from being split again at once",
                       *s.coarsen_threshold, *s.refine_threshold));
  if (a.contains("steady_rate"))
    s.steady_rate = r.non_negative(a["steady_rate"], path + "/steady_rate");
  if (a.contains("min_lifetime"))
    s.min_lifetime = r.non_negative(a["min_lifetime"], path + "/min_lifetime");
  for (const auto& [key, level] :
       {std::pair{"min_level", &s.min_level}, std::pair{"max_level", &s.max_level}}) {
    if (!a.contains(key)) continue;
    *level = r.integer(a[key], path + "/" + key, 0);
    if (**level > 30) r.fail(path + "/" + key, "levels go from 0 (the input's blocks) to 30");
  }
  if (s.min_level && s.max_level && *s.max_level < *s.min_level)
    r.fail(path + "/max_level", fmt::format("max_level ({}) must not be below min_level ({})",
                                            *s.max_level, *s.min_level));
  if (a.contains("max_vertices"))
    s.max_vertices = r.integer(a["max_vertices"], path + "/max_vertices", 0);
  if (a.contains("merge_batch")) {
    s.merge_batch = r.non_negative(a["merge_batch"], path + "/merge_batch");
    if (!(*s.merge_batch < 1.0))
      r.fail(path + "/merge_batch",
             "the merge batch is a fraction of the particles (0.05: merges wait until 5 % of "
             "them can go at once); it must be below 1");
  }
  if (a.contains("even_levels")) s.even_levels = r.boolean(a["even_levels"], path + "/even_levels");
}

void parse_simulate(const Reader& r, const json& j, SimulateSpec& sim) {
  const std::string path = "/simulate";
  r.require_object(j, path, "simulate");
  r.check_keys(
      j, path,
      {"duration", "adaptive", "time_step", "integrator", "solver", "bending", "compression",
       "stop_at_rest", "gravity", "pin_above", "check_body_vertices", "rest", "self_collision"});
  if (j.contains("pin_above")) sim.pin_above = r.number(j["pin_above"], path + "/pin_above");
  if (j.contains("duration")) {
    sim.duration = r.positive(j["duration"], path + "/duration");
    if (sim.duration > kMaxDuration)
      r.fail(path + "/duration",
             fmt::format("a drape of {:.6g} s is longer than the {:g} s (one hour of simulated "
                         "time) allowed; a garment settles within seconds",
                         sim.duration, kMaxDuration));
  }
  if (j.contains("adaptive")) parse_adaptive(r, j["adaptive"], sim);
  if (j.contains("time_step")) {
    sim.time_step = r.positive(j["time_step"], path + "/time_step");
    if (sim.time_step < kMinTimeStep || sim.time_step > kMaxTimeStep)
      r.fail(path + "/time_step",
             fmt::format("a time step of {:.6g} s is outside {:g} .. {:g} s (the step control "
                         "shortens steps itself when it needs to; 1/60 s is the default)",
                         sim.time_step, kMinTimeStep, kMaxTimeStep));
  }
  if (j.contains("integrator")) {
    sim.integrator = r.text(j["integrator"], path + "/integrator");
    if (sim.integrator != "implicit-euler" && sim.integrator != "bdf2")
      r.fail(path + "/integrator", fmt::format("unknown integrator '{}'; use \"implicit-euler\" "
                                               "or \"bdf2\"",
                                               sim.integrator));
  }
  if (j.contains("solver")) {
    sim.solver = r.text(j["solver"], path + "/solver");
    if (sim.solver != "pcg" && sim.solver != "cholmod")
      r.fail(path + "/solver",
             fmt::format("unknown solver '{}'; use \"pcg\" or \"cholmod\"", sim.solver));
  }
  if (j.contains("bending")) {
    sim.bending = r.text(j["bending"], path + "/bending");
    if (sim.bending != "hinges" && sim.bending != "quadratic")
      r.fail(
          path + "/bending",
          fmt::format("unknown bending model '{}'; use \"hinges\" or \"quadratic\"", sim.bending));
  }
  if (j.contains("compression")) {
    sim.compression = r.text(j["compression"], path + "/compression");
    if (sim.compression != "linear" && sim.compression != "buckling")
      r.fail(path + "/compression",
             fmt::format("unknown compression model '{}'; use \"linear\" or \"buckling\"",
                         sim.compression));
  }
  if (j.contains("stop_at_rest"))
    sim.stop_at_rest = r.boolean(j["stop_at_rest"], path + "/stop_at_rest");
  if (j.contains("gravity")) {
    sim.gravity = r.vector<3>(j["gravity"], path + "/gravity");
    for (int k = 0; k < 3; ++k)
      if (std::abs(sim.gravity[k]) > kMaxGravity)
        r.fail(fmt::format("{}/gravity/{}", path, k),
               fmt::format("{:.6g} m/s² is outside ±{:g} m/s² (Earth's gravity is 9.81 m/s²)",
                           sim.gravity[k], kMaxGravity));
  }
  if (j.contains("check_body_vertices"))
    sim.check_body_vertices = r.boolean(j["check_body_vertices"], path + "/check_body_vertices");
  if (j.contains("rest")) {
    sim.rest = r.text(j["rest"], path + "/rest");
    if (sim.rest != "flat" && sim.rest != "shaped")
      r.fail(path + "/rest", fmt::format("unknown rest shape '{}'; use \"flat\" (the flattened "
                                         "pattern pieces) or \"shaped\" (as drawn on the body)",
                                         sim.rest));
  }
  if (j.contains("self_collision"))
    sim.self_collision = r.boolean(j["self_collision"], path + "/self_collision");
}

SheetSpec parse_sheet(const Reader& r, const json& j) {
  const std::string path = "/sheet";
  r.require_object(j, path, "sheet");
  r.check_keys(j, path,
               {"size", "resolution", "orientation", "centre", "pins", "layers", "layer_offset",
                "layer_turn", "shape"});
  SheetSpec sheet;
  if (j.contains("layers")) sheet.layers = r.integer(j["layers"], path + "/layers", 1);
  if (j.contains("layer_offset"))
    sheet.layer_offset = r.vector<3>(j["layer_offset"], path + "/layer_offset");
  if (j.contains("layer_turn")) sheet.layer_turn = r.number(j["layer_turn"], path + "/layer_turn");
  if (j.contains("size")) {
    sheet.size = r.vector<2>(j["size"], path + "/size");
    for (int k = 0; k < 2; ++k)
      if (!(sheet.size[k] > 0))
        r.fail(fmt::format("{}/size/{}", path, k), "a sheet's width and height must be positive");
    for (int k = 0; k < 2; ++k)
      if (sheet.size[k] > kMaxSheetSide)
        r.fail(fmt::format("{}/size/{}", path, k),
               out_of_range_sentence(sheet.size[k], 0, kMaxSheetSide, "a sheet side of"));
  }
  if (j.contains("resolution")) {
    const json& res = j["resolution"];
    if (!res.is_array() || res.size() != 2)
      r.fail(path + "/resolution", "expected [columns, rows] of quads");
    sheet.columns = r.integer(res[0], path + "/resolution/0", 1);
    sheet.rows = r.integer(res[1], path + "/resolution/1", 1);
    if (sheet.columns > 1024 || sheet.rows > 1024)
      r.fail(path + "/resolution", "a sheet has at most 1024 quads along a side");
  }
  if (j.contains("orientation")) {
    const std::string o = r.text(j["orientation"], path + "/orientation");
    if (o != "vertical" && o != "horizontal")
      r.fail(path + "/orientation",
             fmt::format("unknown orientation '{}'; use \"vertical\" or \"horizontal\"", o));
    sheet.horizontal = o == "horizontal";
  }
  if (j.contains("centre")) sheet.centre = r.position<3>(j["centre"], path + "/centre");
  if (j.contains("shape")) {
    const std::string shape = r.text(j["shape"], path + "/shape");
    if (shape != "rectangle" && shape != "disc")
      r.fail(path + "/shape",
             fmt::format("unknown shape '{}'; use \"rectangle\" or \"disc\"", shape));
    sheet.disc = shape == "disc";
    if (sheet.disc && sheet.size[1] != sheet.size[0])
      r.fail(path + "/size", "a disc's size is [diameter, diameter]: give the same length twice");
    if (sheet.disc && sheet.rows != sheet.columns)
      r.fail(path + "/resolution",
             "a disc's resolution is [cells, cells] across its diameter: give the same count "
             "twice");
    if (sheet.disc && sheet.columns < 4)
      r.fail(path + "/resolution", "a disc needs at least 4 cells across its diameter");
  }
  if (j.contains("pins")) {
    const json& pins = j["pins"];
    if (!pins.is_array()) r.fail(path + "/pins", "expected a list of corner or edge names");
    static constexpr std::string_view kNames[] = {
        "top-left", "top-right", "bottom-left", "bottom-right", "top", "bottom", "left", "right"};
    for (size_t i = 0; i < pins.size(); ++i) {
      const std::string pp = fmt::format("{}/pins/{}", path, i);
      const std::string name = r.text(pins[i], pp);
      // A clamp "top:N" holds N lines of vertices from that edge (a cantilever's clamp).
      const std::size_t colon = name.find(':');
      const std::string edge = name.substr(0, colon);
      const bool clamp = colon != std::string::npos &&
                         (edge == "top" || edge == "bottom" || edge == "left" || edge == "right");
      if (edge == "centre" && colon != std::string::npos) {
        // A clamp at the centre: "centre:0.09" holds the vertices within 9 cm (Cusick's support).
        const std::string number = name.substr(colon + 1);
        double radius = 0.0;
        try {
          std::size_t used = 0;
          radius = std::stod(number, &used);
          if (used != number.size()) radius = 0.0;
        } catch (const std::exception&) {
          radius = 0.0;
        }
        const double largest = 0.5 * std::min(sheet.size[0], sheet.size[1]);
        if (!(radius > 0.0 && radius < largest))
          r.fail(pp, fmt::format("the clamp '{}' must give a radius in metres between 0 and {} "
                                 "(half the sheet), e.g. centre:0.09",
                                 name, largest));
      } else if (sheet.disc) {
        r.fail(pp, fmt::format("a disc is held only by a clamp at its centre (centre:R, R in "
                               "metres), not by '{}'",
                               name));
      } else if (clamp) {
        const std::string digits = name.substr(colon + 1);
        const int lines = (edge == "top" || edge == "bottom" ? sheet.rows : sheet.columns) + 1;
        const bool number = !digits.empty() && digits.size() < 7 &&
                            std::all_of(digits.begin(), digits.end(),
                                        [](char ch) { return ch >= '0' && ch <= '9'; });
        if (!number || std::stoi(digits) < 1 || std::stoi(digits) > lines)
          r.fail(pp, fmt::format("the clamp '{}' must hold 1 to {} lines of vertices ({}:N)", name,
                                 lines, edge));
      } else if (std::find(std::begin(kNames), std::end(kNames), name) == std::end(kNames)) {
        r.fail(pp, fmt::format("unknown pin '{}'; use a corner (top-left, top-right, bottom-left, "
                               "bottom-right), an edge (top, bottom, left, right) or a clamp of "
                               "several lines of vertices (top:3)",
                               name));
      }
      sheet.pins.push_back(name);
    }
  }
  return sheet;
}

// "pattern": true, false, or an object of settings.
void parse_pattern(const Reader& r, const json& j, OutputSpec& out) {
  const std::string path = "/output/pattern";
  if (j.is_boolean()) {
    if (j.get<bool>()) out.pattern = PatternSpec{};
    return;
  }
  r.require_object(j, path, "true, false or an object of pattern settings");
  r.check_keys(j, path, {"fabric_width", "seam_allowance", "max_stretch"});
  PatternSpec spec;
  if (j.contains("fabric_width"))
    spec.fabric_width = r.positive(j["fabric_width"], path + "/fabric_width");
  if (j.contains("seam_allowance")) {
    spec.seam_allowance = r.number(j["seam_allowance"], path + "/seam_allowance");
    if (spec.seam_allowance < 0 || spec.seam_allowance > 0.1)
      r.fail(path + "/seam_allowance",
             fmt::format("seam allowance {} m is outside 0 .. 0.1 m", spec.seam_allowance));
  }
  if (j.contains("max_stretch"))
    spec.max_stretch = r.positive(j["max_stretch"], path + "/max_stretch");
  out.pattern = spec;
}

void parse_output(const Reader& r, const json& j, OutputSpec& out) {
  const std::string path = "/output";
  r.require_object(j, path, "output");
  r.check_keys(j, path, {"images", "mesh", "report", "wireframe", "pattern"});
  if (j.contains("mesh")) {
    out.mesh = r.text(j["mesh"], path + "/mesh");
    if (!out.mesh.ends_with(".obj") && !out.mesh.ends_with(".glb"))
      r.fail(path + "/mesh", fmt::format("'{}' must end in .obj or .glb", out.mesh));
    if (out.mesh.find('/') != std::string::npos)
      r.fail(path + "/mesh", "give a file name only; the directory comes from -o");
  }
  if (j.contains("report")) out.report = r.boolean(j["report"], path + "/report");
  if (j.contains("wireframe")) out.wireframe = r.boolean(j["wireframe"], path + "/wireframe");
  if (j.contains("pattern")) parse_pattern(r, j["pattern"], out);
  if (j.contains("images")) {
    out.images_listed = true;
    const json& images = j["images"];
    if (!images.is_array()) r.fail(path + "/images", "expected a list of images");
    r.check_count(images, path + "/images", kMaxImages, "images");
    for (size_t i = 0; i < images.size(); ++i) {
      const std::string ip = fmt::format("{}/images/{}", path, i);
      const json& im = images[i];
      r.require_object(im, ip, "an image");
      r.check_keys(im, ip, {"view", "size", "wireframe"});
      ImageSpec image;
      if (im.contains("view")) {
        const json& v = im["view"];
        if (v.is_string() && v.get<std::string>() == "three-quarter") {
          image.view = "three-quarter";
        } else {
          const ViewSpec view = r.view(v, ip + "/view");
          image.view = view.name();
          image.camera = view.camera;
        }
      }
      if (im.contains("size")) {
        const json& s = im["size"];
        if (!s.is_array() || s.size() != 2)
          r.fail(ip + "/size", "expected [width, height] in pixels");
        image.width = r.integer(s[0], ip + "/size/0", 16);
        image.height = r.integer(s[1], ip + "/size/1", 16);
        if (image.width > kMaxImageSide || image.height > kMaxImageSide)
          r.fail(ip + "/size", fmt::format("images are at most {} pixels on a side (a {}x{} "
                                           "picture takes half a gigabyte to draw)",
                                           kMaxImageSide, kMaxImageSide, kMaxImageSide));
      }
      if (im.contains("wireframe")) image.wireframe = r.boolean(im["wireframe"], ip + "/wireframe");
      out.images.push_back(image);
    }
  }
}

// "line 3, column 7" from a byte offset.
std::string position_of(std::string_view text, size_t byte) {
  byte = std::min(byte, text.size());
  size_t line = 1, column = 1;
  for (size_t i = 0; i + 1 < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return fmt::format("line {}, column {}", line, column);
}

constexpr int kMaxNesting = 64;

// Tracks the JSON path while nlohmann's parser reports events, to reject a key given twice in
// one object (JSON allows it and keeps the last value, silently dropping the first).
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(const Sketch& sketch) : sketch_(sketch) {}

  bool operator()(int depth, json::parse_event_t event, json& parsed) {
    // A sketch file nests a few levels (a point in a list in a curve in the list of curves);
    // thousands of levels are a damaged or hostile file, and cost time and memory to build.
    if (depth > kMaxNesting)
      sketch_.fail(path(), fmt::format("lists and objects are nested more than {} levels deep "
                                       "here; a sketch file needs fewer than 10",
                                       kMaxNesting));
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        enter_element();
        frames_.push_back({event == json::parse_event_t::array_start, -1, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          sketch_.fail(path(),
                       fmt::format("the key '{}' is given twice in this object; JSON would keep "
                                   "only the last one: remove one of them",
                                   f.key));
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        break;
      case json::parse_event_t::value:
        enter_element();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array = false;
    long index = -1;
    std::set<std::string> keys;
    std::string key;
  };

  // A value or container begins: in an array it is the next element.
  void enter_element() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }

  // "/a/0/b": keys with JSON Pointer escapes (~0 for ~, ~1 for /).
  std::string path() const {
    std::string out;
    for (const Frame& f : frames_) {
      if (f.array) {
        out += "/" + std::to_string(f.index);
        continue;
      }
      out += "/";
      for (char c : f.key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    }
    return out;
  }

  const Sketch& sketch_;
  std::vector<Frame> frames_;
};

}  // namespace

std::string ViewSpec::name() const {
  switch (kind) {
    case ViewKind::kFront:
      return "front";
    case ViewKind::kBack:
      return "back";
    case ViewKind::kLeft:
      return "left";
    case ViewKind::kRight:
      return "right";
    case ViewKind::kCamera:
      return "camera";
  }
  return "?";
}

void Sketch::fail(const std::string& json_path, const std::string& sentence) const {
  throw SketchError(file, json_path, sentence);
}

const CurveSpec* Sketch::find_curve(std::string_view id) const {
  for (const CurveSpec& c : curves)
    if (c.id == id) return &c;
  return nullptr;
}

const PanelSpec* Sketch::find_panel(std::string_view id) const {
  for (const PanelSpec& p : panels)
    if (p.id == id) return &p;
  return nullptr;
}

std::filesystem::path Sketch::resolve(const std::string& relative) const {
  const std::filesystem::path p(relative);
  return p.is_absolute() ? p : base_dir / p;
}

Sketch parse_sketch(std::string_view text, const std::string& file,
                    const std::filesystem::path& base_dir) {
  Sketch sketch;
  sketch.file = file;
  sketch.base_dir = base_dir;
  const Reader r(sketch);

  // UTF-16 (what some Windows editors save): a byte-order mark, or ASCII text whose every
  // other byte is zero.
  const auto utf16 = [&] {
    if (text.starts_with("\xff\xfe") || text.starts_with("\xfe\xff")) return true;
    if (text.size() < 4) return false;
    const size_t zero = text[0] == '\0' ? 0 : 1;  // big- or little-endian
    for (size_t i = 0; i + 1 < std::min<size_t>(text.size(), 64); i += 2)
      if (text[i + zero] != '\0' || text[i + 1 - zero] == '\0') return false;
    return true;
  };
  if (utf16())
    r.fail("",
           "the file is UTF-16 text; this program reads sketch files in UTF-8 (save it as "
           "UTF-8 in the editor)");
  // A NUL byte would end the text for the JSON reader, silently dropping the rest.
  if (const size_t nul = text.find('\0'); nul != std::string_view::npos)
    r.fail("", fmt::format("{}: the file holds a NUL byte (a zero byte); a sketch file is text: "
                           "the file is damaged or not a sketch file",
                           position_of(text, nul + 1)));
  json root;
  try {
    DuplicateKeyCheck duplicates(sketch);
    root =
        json::parse(mark_overflowing_numbers(text), std::ref(duplicates), /*allow_exceptions=*/true,
                    /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    std::string detail = e.what();
    const size_t colon = detail.find("error while parsing");
    if (colon != std::string::npos) detail = detail.substr(colon);
    r.fail("",
           fmt::format("{}: the file is not valid JSON ({})", position_of(text, e.byte), detail));
  }
  r.require_object(root, "", "a sketch file");
  r.check_keys(root, "",
               {"format", "body", "edge_length", "offset", "junction_tolerance", "corner_angle",
                "relax_iterations", "fabric", "garment_mesh", "curves", "panels", "join",
                "simulate", "output", "sheet"});
  if (root.contains("format")) {
    const std::string format = r.text(root["format"], "/format");
    if (format != kSketchFormat)
      r.fail("/format",
             fmt::format("this program reads format \"{}\", not \"{}\"", kSketchFormat, format));
  }
  if (root.contains("body")) parse_body(r, root["body"], sketch.body);
  if (root.contains("edge_length")) {
    sketch.edge_length = r.positive(root["edge_length"], "/edge_length");
    if (sketch.edge_length < 0.002 || sketch.edge_length > 0.5)
      r.fail("/edge_length",
             fmt::format("an edge length of {} m is outside 2 mm .. 50 cm", sketch.edge_length));
  }
  if (root.contains("offset")) sketch.offset = r.number(root["offset"], "/offset");
  if (root.contains("junction_tolerance"))
    sketch.junction_tolerance = r.positive(root["junction_tolerance"], "/junction_tolerance");
  if (sketch.junction_tolerance > kMaxJunctionTolerance)
    r.fail("/junction_tolerance",
           out_of_range_sentence(sketch.junction_tolerance, 0, kMaxJunctionTolerance,
                                 "a junction tolerance of"));
  if (root.contains("corner_angle")) {
    sketch.corner_angle_degrees = r.positive(root["corner_angle"], "/corner_angle");
    if (sketch.corner_angle_degrees >= 180)
      r.fail("/corner_angle", "a corner angle is a turn in degrees below 180");
  }
  if (root.contains("relax_iterations"))
    sketch.relax_iterations = r.integer(root["relax_iterations"], "/relax_iterations", 0);
  if (sketch.relax_iterations > kMaxRelaxIterations)
    r.fail("/relax_iterations", fmt::format("{} sweeps is more than the {} allowed",
                                            sketch.relax_iterations, kMaxRelaxIterations));
  if (root.contains("fabric")) {
    // A preset name, a path to a fabric file, or the fabric's constants inline (the presets'
    // schema, checked when the scene is built).
    if (root["fabric"].is_object()) {
      sketch.fabric_inline = root["fabric"].dump();
      sketch.fabric = root["fabric"].contains("name") && root["fabric"]["name"].is_string()
                          ? root["fabric"]["name"].get<std::string>()
                          : "custom";
    } else {
      sketch.fabric = r.text(root["fabric"], "/fabric");
    }
  }
  if (root.contains("simulate")) parse_simulate(r, root["simulate"], sketch.simulate);
  if (root.contains("output")) parse_output(r, root["output"], sketch.output);

  if (root.contains("sheet")) {
    sketch.sheet = parse_sheet(r, root["sheet"]);
    for (const char* key : {"curves", "panels", "garment_mesh", "join"})
      if (root.contains(key))
        r.fail("/sheet", fmt::format("a sheet scene has no \"{}\": remove one or the other", key));
    if (!root.contains("body"))
      sketch.body.mesh = "none";  // a sheet falls freely unless given a body
    return sketch;
  }

  if (root.contains("garment_mesh")) {
    sketch.garment_mesh = r.text(root["garment_mesh"], "/garment_mesh");
    if (root.contains("curves") || root.contains("panels"))
      r.fail("/garment_mesh",
             "a file with \"garment_mesh\" skips sketching: remove \"curves\" "
             "and \"panels\" (or remove \"garment_mesh\")");
    return sketch;
  }

  if (!root.contains("curves")) r.fail("", "the file has no \"curves\"");
  const json& curves = root["curves"];
  if (!curves.is_array()) r.fail("/curves", "expected a list of curves");
  if (curves.empty()) r.fail("/curves", "the list of curves is empty");
  r.check_count(curves, "/curves", kMaxCurves, "curves");
  for (size_t i = 0; i < curves.size(); ++i) {
    CurveSpec curve = parse_curve(r, curves[i], fmt::format("/curves/{}", i), sketch);
    if (const CurveSpec* other = sketch.find_curve(curve.id))
      r.fail(curve.json_path + "/id", fmt::format("two curves have the id '{}' ({} and {})",
                                                  curve.id, other->json_path, curve.json_path));
    sketch.curves.push_back(std::move(curve));
  }

  if (!root.contains("panels")) r.fail("", "the file has no \"panels\"");
  const json& panels = root["panels"];
  if (!panels.is_array()) r.fail("/panels", "expected a list of panels");
  if (panels.empty())
    r.fail("/panels", "the list of panels is empty: a garment needs at least one panel");
  r.check_count(panels, "/panels", kMaxPanels, "panels");
  for (size_t i = 0; i < panels.size(); ++i) {
    PanelSpec panel = parse_panel(r, panels[i], fmt::format("/panels/{}", i), sketch);
    if (const PanelSpec* other = sketch.find_panel(panel.id))
      r.fail(panel.json_path + "/id", fmt::format("two panels have the id '{}' ({} and {})",
                                                  panel.id, other->json_path, panel.json_path));
    sketch.panels.push_back(std::move(panel));
  }
  if (root.contains("join")) {
    const json& joins = root["join"];
    if (!joins.is_array()) r.fail("/join", "expected a list of {\"id\": ..., \"panels\": [...]}");
    std::set<std::string> joined;
    for (size_t i = 0; i < joins.size(); ++i) {
      const std::string ip = fmt::format("/join/{}", i);
      const json& jj = joins[i];
      r.require_object(jj, ip, "a join");
      r.check_keys(jj, ip, {"id", "panels"});
      JoinSpec join;
      join.json_path = ip;
      if (!jj.contains("id")) r.fail(ip, "a join needs an \"id\" for the merged panel");
      join.id = r.identifier(jj["id"], ip + "/id");
      if (!jj.contains("panels") || !jj["panels"].is_array() || jj["panels"].size() < 2)
        r.fail(ip + "/panels", "a join lists at least two panel ids");
      for (size_t k = 0; k < jj["panels"].size(); ++k) {
        const std::string kp = fmt::format("{}/panels/{}", ip, k);
        const std::string id = r.text(jj["panels"][k], kp);
        const bool is_copy = id.ends_with(".mirror");
        const PanelSpec* p = sketch.find_panel(is_copy ? id.substr(0, id.size() - 7) : id);
        if (p == nullptr) r.fail(kp, fmt::format("panel '{}' is not defined", id));
        if (is_copy && !p->mirror)
          r.fail(kp, fmt::format("panel '{}' has no mirror copy (set \"mirror\": true on '{}')", id,
                                 p->id));
        if (!joined.insert(id).second)
          r.fail(kp, fmt::format("panel '{}' is already part of a join", id));
        join.panels.push_back(id);
      }
      for (const JoinSpec& other : sketch.joins)
        if (other.id == join.id)
          r.fail(ip + "/id", fmt::format("two joins have the id '{}'", join.id));
      sketch.joins.push_back(std::move(join));
    }
  }
  return sketch;
}

Sketch load_sketch(const std::filesystem::path& path) {
  if (const auto problem = input_file_problem(path, kMaxSketchFileBytes))
    throw SketchError(path.string(), "", "the sketch file " + *problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const bool exists = std::filesystem::exists(path);
    throw SketchError(path.string(), "",
                      exists ? "the sketch file cannot be read" : "the sketch file does not exist");
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse_sketch(buffer.str(), path.string(), path.parent_path());
}

}  // namespace sd::garment
