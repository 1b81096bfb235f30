#pragma once
// Inside the scene layer: reading a sketch file's JSON with what a message needs. Reader checks
// each value's type and range and fails with the file, the JSON path and a sentence
// (SketchError); strict_json_check (sim/strict_json.hpp) follows nlohmann's parser to refuse a key
// given twice; numbers that overflow a double are marked before parsing so that they are refused at
// their path too. The parsers of the file's sections (sketch_sections.hpp) use them; nothing
// outside scene/ does.

#include <fmt/format.h>

#include <Eigen/Core>
#include <array>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "garment/garment_request.hpp"
#include "garment/sketch_ranges.hpp"
#include "scene/sketch_file.hpp"
#include "sim/edit_distance.hpp"
#include "sim/strict_json.hpp"

namespace sd::scene::detail {

// The garment request's types, SketchError and the input limits (garment/sketch_ranges.hpp) by
// name, in the parsers' own namespace only.
using namespace garment;
using nlohmann::json;

// Levenshtein distance, for "did you mean" hints on misspelt keys and names.
using sim::edit_distance;

// "the text \"x\"", "a list", ...: what a value is, for messages.
std::string type_name(const json& value);

// JSON has no NaN or infinity literal, but a number like 1e999 overflows a double; the JSON
// library rejects it without saying where. Such literals are replaced by a marked string before
// parsing, so the reader reports them with their JSON path.
inline constexpr const char* kOverflowMarker = "\x01sketchdrape-overflow:";
std::string mark_overflowing_numbers(std::string_view text);

// "line 3, column 7" from a byte offset.
std::string position_of(std::string_view text, size_t byte);

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
      std::string sentence = fmt::format("unknown key '{}'", garment::excerpt(key));
      if (!best.empty())
        sentence += fmt::format(" (did you mean '{}'?)", best);
      else
        sentence += fmt::format(" (known keys here: {})", fmt::join(known, ", "));
      fail(path + "/" + garment::excerpt(key), sentence);
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
                       garment::excerpt(std::string_view(value.get<std::string>())
                                            .substr(std::string_view(kOverflowMarker).size()))));
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

  // A whole number from min_value; with max_value, at most that, and the message gives both
  // (trial 39, P16: "at least 0, got 1e23" for a value whose range is 0 .. 1000).
  int integer(const json& value, const std::string& path, int min_value,
              std::optional<int> max_value = std::nullopt) const {
    const double x = number(value, path);
    if (x != std::floor(x) || x < min_value || x > max_value.value_or(10000000))
      fail(path, max_value ? fmt::format("expected a whole number from {} to {}, got {}", min_value,
                                         *max_value, value.dump())
                           : fmt::format("expected a whole number of at least {}, got {}",
                                         min_value, value.dump()));
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
    // An id names a panel or a curve in every message, in garment.obj's groups and in
    // report.json: a 100,000-character id was written into all of them (trial 39, P17).
    if (id.size() > kMaxIdLength)
      fail(path, fmt::format("an id may have at most {} characters, and '{}' is longer: give a "
                             "short name, such as 'front' or 'hem_b'",
                             kMaxIdLength, garment::excerpt(id, 20)));
    const bool ok = std::all_of(id.begin(), id.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!ok)
      fail(path,
           fmt::format(
               "id '{}' may only use ASCII letters (a-z, A-Z; no accents), digits, '_' and '-'",
               garment::excerpt(id)));
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
             out_of_range_sentence(v[k], -kMaxCoordinate, kMaxCoordinate, "the coordinate",
                                   garment::kUsualCoordinate));
    return v;
  }

  // An edge length in metres: 2 mm .. 50 cm.
  double edge_length(const json& value, const std::string& path) const {
    const double x = positive(value, path);
    if (x < garment::kMinEdgeLength || x > 0.5)
      fail(path, out_of_range_sentence(x, garment::kMinEdgeLength, 0.5, "an edge length of",
                                       garment::kUsualEdgeLength));
    return x;
  }

  // A list of at most `most` entries at `path`.
  void check_count(const json& list, const std::string& path, size_t most,
                   std::string_view what) const {
    if (list.is_array() && list.size() > most)
      fail(path, fmt::format("{} {} is more than the {} allowed", list.size(), what, most));
  }

  // "there is no view called 'x' (did you mean 'y'?); the views are a, b, ... or a camera".
  static std::string unknown_view_sentence(const std::string& name,
                                           const std::vector<std::string_view>& names) {
    std::string best;
    // Words a designer uses for a view, where the nearest spelling is another view ("rear" is
    // two letters from "left"); a synonym is offered only when its view is one of `names`.
    static constexpr std::array<std::pair<std::string_view, std::string_view>, 10> kSynonyms{{
        {"rear", "back"},
        {"behind", "back"},
        {"frontal", "front"},
        {"face", "front"},
        {"side", "left' or 'right"},
        {"profile", "left' or 'right"},
        {"3/4", "three-quarter"},
        {"quarter", "three-quarter"},
        {"oblique", "three-quarter"},
        {"above", "top"},
    }};
    for (const auto& [word, view] : kSynonyms) {
      const std::string_view first = view.substr(0, view.find('\''));
      if (word == name && std::find(names.begin(), names.end(), first) != names.end()) best = view;
    }
    size_t best_distance = 4;  // close spellings only ("thre-quater", "frnt")
    for (std::string_view n : names)
      if (const size_t d = edit_distance(name, n); best.empty() && d < best_distance)
        best = n, best_distance = d;
    std::string list;
    for (size_t i = 0; i < names.size(); ++i)
      list += std::string(i == 0 ? "" : ", ") + std::string(names[i]);
    return fmt::format(
        "there is no view called '{}'{}; the views are {} or a camera {{\"camera\": {{\"eye\": "
        "[...], \"target\": [...]}}}}",
        name, best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best), list);
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
      fail(path, unknown_view_sentence(name, {"front", "back", "left", "right"}));
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

// The sketch's callback for nlohmann's parser: a key given twice in one object, or nesting deeper
// than a sketch needs, is refused at its JSON path (sim::StrictJsonCallback follows the events).
inline sim::StrictJsonCallback strict_json_check(const Sketch& sketch) {
  // A sketch file nests a few levels (a point in a list in a curve in the list of curves).
  return sim::StrictJsonCallback(
      [&sketch](const std::string& path, const std::string& sentence) {
        sketch.fail(path, sentence);
      },
      "a sketch file", 10);
}

}  // namespace sd::scene::detail
