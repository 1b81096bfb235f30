#include "scene/sketch_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <functional>
#include <sstream>

#include "garment/input_checks.hpp"
#include "scene/sketch_sections.hpp"

namespace sd::scene {

using namespace detail;  // the reader and the sections' parsers

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
  // gzip's magic bytes (trial 41, P9: "line 1, column 4: the file holds a NUL byte").
  if (text.starts_with("\x1f\x8b"))
    r.fail("",
           "the file is gzip-compressed (it starts with gzip's bytes 1f 8b): unpack it first "
           "(gunzip) and give the unpacked .json file");
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
    root = json::parse(mark_overflowing_numbers(text), strict_json_check(sketch),
                       /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    // Nothing but blanks and comments (trial 44, P9: an empty file was "not valid JSON
    // (unexpected end of input ...)"): an editor that failed to save, a truncated copy.
    if (json::accept(std::string(text) + "\nnull", /*ignore_comments=*/true)) {
      const bool blank = std::all_of(text.begin(), text.end(), [](char c) {
        return std::isspace(static_cast<unsigned char>(c)) != 0;
      });
      r.fail("", fmt::format("the file {}: a sketch is an object {{\"curves\": [...], "
                             "\"panels\": [...]}} (did the editor fail to save, or the copy "
                             "stop short?)",
                             text.empty() ? "is empty (0 bytes)"
                             : blank      ? "holds only blanks"
                                          : "holds only comments"));
    }
    std::string detail = e.what();
    const size_t colon = detail.find("error while parsing");
    if (colon != std::string::npos) detail = detail.substr(colon);
    // NaN and Infinity as JavaScript and Python write them: say why they are refused.
    size_t start = std::min<size_t>(e.byte, text.size());
    while (start > 0 && std::isalpha(static_cast<unsigned char>(text[start - 1]))) --start;
    std::string word(text.substr(start, 3));
    for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const std::string hint =
        word == "nan" || word == "inf"
            ? "; NaN and Infinity are not numbers in JSON: every number must be finite"
            : "";
    // The common slips in a designer's words (trial 40 P13): the parser's say "invalid literal".
    const size_t at = std::min<size_t>(e.byte, text.size());
    const char last = at > 0 ? text[at - 1] : '\0';
    size_t before = at > 0 ? at - 1 : 0;
    while (before > 0 && std::isspace(static_cast<unsigned char>(text[before - 1]))) --before;
    std::string plain;
    if (last == '+')
      plain = "a number cannot start with '+': write 0.1, not +0.1";
    else if ((last == 'x' || last == 'X') && at >= 2 && text[at - 2] == '0')
      plain = "numbers are decimal in JSON: write 16, not 0x10";
    else if (last == '\'')
      plain = "text is written in double quotes (\"top\"), not single quotes ('top')";
    else if ((last == ']' || last == '}') && before > 0 && text[before - 1] == ',')
      plain = fmt::format(
          "a comma before '{}' (after the last item) is not allowed in JSON: "
          "remove it",
          last);
    if (!plain.empty())
      r.fail("",
             fmt::format("{}: the file is not valid JSON: {}", position_of(text, e.byte), plain));
    const std::string not_utf8 =
        detail.find("ill-formed UTF-8") != std::string::npos
            ? "; the file is not UTF-8 text (Latin-1 or a Windows code page?): save it as UTF-8 "
              "in the editor"
            : "";
    r.fail("", fmt::format("{}: the file is not valid JSON ({}){}{}", position_of(text, e.byte),
                           detail, hint, not_utf8));
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
    // The same range and centimetres hint as a curve's or panel's edge_length.
    sketch.edge_length = r.edge_length(root["edge_length"], "/edge_length");
  }
  if (root.contains("offset")) sketch.offset = r.number(root["offset"], "/offset");
  if (root.contains("junction_tolerance"))
    sketch.junction_tolerance = r.positive(root["junction_tolerance"], "/junction_tolerance");
  if (sketch.junction_tolerance > kMaxJunctionTolerance)
    r.fail("/junction_tolerance",
           out_of_range_sentence(sketch.junction_tolerance, 0, kMaxJunctionTolerance,
                                 "a junction tolerance of", kUsualJunctionTolerance));
  if (root.contains("corner_angle")) {
    sketch.corner_angle_degrees = r.positive(root["corner_angle"], "/corner_angle");
    if (sketch.corner_angle_degrees >= 180)
      r.fail("/corner_angle", "a corner angle is a turn in degrees below 180");
  }
  if (root.contains("relax_iterations"))
    sketch.relax_iterations =
        r.integer(root["relax_iterations"], "/relax_iterations", 0, kMaxRelaxIterations);
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
  parse_garment(r, root, sketch);
  return sketch;
}

Sketch load_sketch(const std::filesystem::path& path) {
  // The shell convention for standard input (trial 41, P13: "-: the sketch file does not
  // exist"); a file really named "-" is still read.
  if (path == "-" && !std::filesystem::exists(path))
    throw SketchError(path.string(), "",
                      "reading a sketch from standard input ('-') is not supported: save it to "
                      "a file and give the file's name (its paths, such as the body's, are "
                      "relative to that file's folder)");
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

}  // namespace sd::scene
