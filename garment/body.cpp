#include "garment/body.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "garment/body_facing.hpp"
#include "garment/body_landmarks.hpp"
#include "garment/body_up_error.hpp"
#include "garment/input_checks.hpp"
#include "garment/sketch_error.hpp"
#include "garment/sketch_ranges.hpp"

namespace sd::garment {
namespace {

// File units: a body outside these without "height" or "scale" is refused rather than guessed
// (kilometres give 0.0018, micrometres 1.8e6).
constexpr double kMinGuessedHeight = 1e-4;
constexpr double kMaxGuessedHeight = 1e7;

constexpr const char* kBuiltinPath = "/usr/share/assimp/models/BLEND/HUMAN.blend";
constexpr double kBuiltinHeight = 1.75;

void collect_meshes(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                    std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>& faces,
                    Eigen::Index& mesh_count) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    if (!(mesh.mPrimitiveTypes & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON))) continue;
    const int base = static_cast<int>(vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      bool in_range = face.mNumIndices >= 3;  // points and lines are not surface
      for (unsigned k = 0; in_range && k < face.mNumIndices; ++k)
        in_range = face.mIndices[k] < mesh.mNumVertices;
      if (!in_range) continue;
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)  // fan; planar convex polygons
        faces.emplace_back(base + static_cast<int>(face.mIndices[0]),
                           base + static_cast<int>(face.mIndices[k]),
                           base + static_cast<int>(face.mIndices[k + 1]));
    }
    ++mesh_count;
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    collect_meshes(scene, *node.mChildren[c], transform, vertices, faces, mesh_count);
}

// Rotation taking the file's `up` to +Y and its facing direction to +Z (proper rotation).
Eigen::Matrix3d frame_rotation(const AxisDirection& up, const AxisDirection& facing) {
  Eigen::Vector3d u = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
  u[up.axis] = up.sign;
  f[facing.axis] = facing.sign;
  Eigen::Matrix3d rows;
  rows.row(0) = u.cross(f).transpose();  // x' = y' × z'
  rows.row(1) = u.transpose();
  rows.row(2) = f.transpose();
  return rows;
}

// Merges vertices closer than `tolerance` (files split vertices along UV and normal seams, which
// would leave the body open), drops faces that collapse or whose area is not above `min_area`,
// and removes vertices no face uses.
struct CleanupCounts {
  Eigen::Index merged_vertices = 0;
  Eigen::Index dropped_faces = 0;
  Eigen::Index duplicate_faces = 0;  // a face given again on the same three corners
  Eigen::Index unused_vertices = 0;
};

CleanupCounts weld_and_clean(meshing::TriMesh& mesh, double tolerance, double min_area) {
  CleanupCounts counts;
  const Eigen::Index nv = mesh.vertex_count();
  // Sort by x, then merge each vertex into the first earlier one within tolerance (sweep window).
  std::vector<Eigen::Index> order(static_cast<size_t>(nv));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    return mesh.vertices(a, 0) < mesh.vertices(b, 0);
  });
  std::vector<Eigen::Index> target(static_cast<size_t>(nv));
  std::iota(target.begin(), target.end(), Eigen::Index{0});
  const double tol2 = tolerance * tolerance;
  for (size_t i = 0; i < order.size(); ++i) {
    const Eigen::Index v = order[i];
    for (size_t j = i; j-- > 0;) {
      const Eigen::Index u = order[j];
      if (mesh.vertices(v, 0) - mesh.vertices(u, 0) > tolerance) break;
      if (target[u] == u && (mesh.vertices.row(v) - mesh.vertices.row(u)).squaredNorm() <= tol2) {
        target[v] = u;
        ++counts.merged_vertices;
        break;
      }
    }
  }
  // Keep faces with three distinct welded corners and a non-zero area, each once: an export that
  // writes every face twice (trial 40), in either orientation, made every edge non-manifold.
  std::vector<Eigen::Vector3i> faces;
  std::set<std::array<int, 3>> corners_seen;
  faces.reserve(static_cast<size_t>(mesh.face_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) t[k] = static_cast<int>(target[mesh.faces(f, k)]);
    const Eigen::Vector3d a = mesh.vertices.row(t[0]), b = mesh.vertices.row(t[1]),
                          c = mesh.vertices.row(t[2]);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        !(0.5 * (b - a).cross(c - a).norm() > min_area)) {
      ++counts.dropped_faces;
      continue;
    }
    std::array<int, 3> corners{t[0], t[1], t[2]};
    std::sort(corners.begin(), corners.end());
    if (!corners_seen.insert(corners).second) {
      ++counts.duplicate_faces;
      continue;
    }
    faces.push_back(t);
  }
  // Compact: keep only vertices that a face uses.
  std::vector<int> index(static_cast<size_t>(nv), -1);
  int kept = 0;
  for (const auto& t : faces)
    for (int k = 0; k < 3; ++k)
      if (index[t[k]] < 0) index[t[k]] = kept++;
  meshing::TriMesh out;
  out.vertices.resize(kept, 3);
  for (Eigen::Index v = 0; v < nv; ++v)
    if (index[v] >= 0) out.vertices.row(index[v]) = mesh.vertices.row(v);
  out.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) out.faces(static_cast<Eigen::Index>(f), k) = index[faces[f][k]];
  counts.unused_vertices = nv - counts.merged_vertices - kept;
  mesh = std::move(out);
  return counts;
}

// An OBJ file's first defect that assimp refuses without a line (trial 35: "OBJ: vertex index out
// of range", "Validation failed: Mesh  contains no faces"): a vertex without three finite numbers,
// a face with fewer than three corners or a corner past the vertices, or no face at all (a file
// cut short). The sentence names the line; nullopt when the scan finds nothing.
std::optional<std::string> obj_defect(const std::string& file) {
  // Two passes: the vertices counted first (a face may name a vertex given after it), then each
  // line in order, so that the first defect in the file is the one named.
  int vertices = 0;
  {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line))
      if (line.rfind("v ", 0) == 0 || line.rfind("v\t", 0) == 0) ++vertices;
  }
  std::ifstream in(file);
  std::string line;
  int number = 0, faces = 0, seen = 0, last_vertex_line = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string tag;
    words >> tag;
    if (tag == "v") {
      double x = 0, y = 0, z = 0;
      if (!(words >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        return fmt::format("line {} ('{}') is not a vertex of three finite numbers x y z{}", number,
                           excerpt(line),
                           in.peek() == EOF ? ": the file looks cut short; export it again" : "");
      ++seen;
      last_vertex_line = number;
    } else if (tag == "f") {
      ++faces;
      std::vector<long> corners;
      std::string corner;
      while (words >> corner) corners.push_back(std::atol(corner.c_str()));
      if (corners.size() < 3)
        return fmt::format("line {} ('{}') is a face with fewer than three corners", number,
                           excerpt(line));
      for (long c : corners) {
        if (c < 0) c += seen + 1;  // relative: -1 is the last vertex so far
        if (c < 1 || c > vertices)
          return fmt::format(
              "line {} ('{}') is a face on vertex {}, but the file has {} vertices (numbered "
              "from 1)",
              number, excerpt(line), c, vertices);
      }
    }
  }
  if (faces == 0 && vertices > 0)
    return fmt::format(
        "it has {} vertices but no face (the last vertex is line {}): the file looks cut short; "
        "export the body again",
        vertices, last_vertex_line);
  return std::nullopt;
}

// A file named .obj (any case) with a defect obj_defect finds is refused with its line.
void throw_obj_defect(const std::string& file) {
  std::string ext = std::filesystem::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".obj") return;
  if (const std::optional<std::string> defect = obj_defect(file))
    throw BodyError("body file '" + file + "' cannot be read: " + *defect);
}

// A file assimp could not read whose contents are of another kind than its name says: a PLY
// named .obj (trial 43, P9: assimp's OBJ reader said "Invalid face index" and the designer was
// told to export the file again), or a sketch file given where a mesh goes (P13: `render
// dress.json` quoted assimp's PLY reader, "Incorrect magic number"). Refused with what it is.
void throw_misnamed(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  std::string ext = std::filesystem::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string lower = head.substr(0, 3);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "ply" && ext != ".ply")
    throw BodyError(fmt::format(
        "body file '{}' is a PLY file (it begins with 'ply') named {}: assimp picks its reader by "
        "the name, so rename it to .ply",
        file, ext.empty() ? "without an extension" : "'" + ext + "'"));
  const size_t first = head.find_first_not_of(" \t\r\n");
  const bool json_like =
      first != std::string::npos && (head[first] == '{' || head.compare(first, 2, "//") == 0);
  if (json_like &&
      (head.find("\"sketchdrape/1\"") != std::string::npos ||
       head.find("\"curves\"") != std::string::npos || head.find("\"sheet\"") != std::string::npos))
    throw BodyError(fmt::format(
        "'{}' is a sketch file, not a mesh: a body is a mesh file (OBJ, PLY, STL, glTF, FBX, "
        "Collada, ...) or 'builtin'; a sketch names its body in \"body\" (its mesh, with "
        "\"up\", \"facing\", \"scale\": give those to `info` or `render` as --up, --facing, "
        "--scale)",
        file));
}

// The triangles of `file` as assimp reads them, merged, welded and cleaned; file units and axes.
// Repairs are added to body.warnings, the mesh count to body.raw.meshes.
meshing::TriMesh read_body_mesh(const std::string& file, Body& body) {
  if (const auto problem = input_file_problem(file, kMaxMeshFileBytes))
    throw BodyError("body file '" + file + "' " + *problem);
  check_mesh_file_header(file, "body file");
  std::error_code size_ec;
  if (std::filesystem::file_size(file, size_ec) == 0 && !size_ec)
    throw BodyError("body file '" + file + "' is empty (0 bytes)");
  Assimp::Importer importer;
  // Only structure validation: assimp's Triangulate step aborts the process (ai_assert) on some
  // corrupt files (invalid/OutOfMemory.off), so polygons are fan-triangulated here and
  // coincident vertices are welded afterwards.
  const unsigned flags = aiProcess_ValidateDataStructure;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(file, flags);
  } catch (const std::exception& e) {  // assimp catches most of its own; be sure
    throw BodyError("cannot read body file '" + file + "': " + e.what());
  }
  if (scene == nullptr) {
    // assimp's words for a file of no mesh it knows (random bytes named .obj) say nothing to a
    // designer: "Validation failed: aiScene::mNumMeshes is 0".
    const std::string reason = importer.GetErrorString();
    throw_misnamed(file);
    if (reason.find("mNumMeshes is 0") != std::string::npos)
      throw BodyError("body file '" + file +
                      "' holds no mesh: no vertices and faces could be read from it (is it "
                      "really a mesh file of the format its name ends in?)");
    throw_obj_defect(file);
    // assimp's own words otherwise, without its doubled spaces ("Mesh  contains": an empty name).
    std::string words;
    for (const char c : reason)
      if (!(c == ' ' && !words.empty() && words.back() == ' ')) words += c;
    throw BodyError("body file '" + file +
                    "' cannot be read (is it a complete mesh file, exported again if in doubt?); "
                    "the reader, assimp, says: " +
                    words);
  }
  if (scene->mRootNode == nullptr || scene->mNumMeshes == 0)
    throw BodyError("body file '" + file + "' holds no mesh");

  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> tris;
  collect_meshes(*scene, *scene->mRootNode, aiMatrix4x4(), points, tris, body.raw.meshes);
  if (tris.empty()) throw BodyError("body file '" + file + "' holds no triangles");
  if (tris.size() > kMaxBodyTriangles)
    throw BodyError(fmt::format(
        "body file '{}' has {} triangles, more than the {} a body may have (collision needs no "
        "finer body than a few hundred thousand); reduce it first, e.g. with Blender's Decimate "
        "modifier",
        file, tris.size(), kMaxBodyTriangles));
  for (const auto& p : points)
    if (!p.allFinite()) {
      // In an OBJ the line, as for a vertex cut short (trial 40: "v inf 0 0" on line 101).
      throw_obj_defect(file);
      throw BodyError("body file '" + file + "' has NaN or infinite vertex coordinates");
    }

  meshing::TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i)
    mesh.faces.row(static_cast<Eigen::Index>(i)) = tris[i].transpose();

  const double diagonal = meshing::bounding_box(mesh).extent().norm();
  if (!(diagonal > 0))
    throw BodyError("body file '" + file + "' has all its vertices at one point");
  const CleanupCounts cleanup = weld_and_clean(mesh, 1e-6 * diagonal, 1e-12 * diagonal * diagonal);
  if (mesh.face_count() == 0)
    throw BodyError("body file '" + file + "' has no triangle with a non-zero area");
  if (cleanup.duplicate_faces > 0)
    body.warnings.push_back(fmt::format(
        "{} of the {} faces of body file '{}' are given twice (on the same three corners, as a "
        "doubled export writes them); the copies were removed",
        cleanup.duplicate_faces, tris.size(), file));
  if (cleanup.dropped_faces > 0)
    body.warnings.push_back(
        fmt::format("dropped {} degenerate triangle(s) (zero area or repeated corners)",
                    cleanup.dropped_faces));
  if (cleanup.unused_vertices > 0)
    spdlog::debug("removed {} vertices no triangle uses", cleanup.unused_vertices);
  if (cleanup.merged_vertices > 0)
    spdlog::debug("welded {} coincident vertices", cleanup.merged_vertices);
  return mesh;
}

// Volume enclosed by a closed mesh (divergence theorem over the faces), positive when the faces
// point outward; file units³. Computed about the centroid to keep far-off files accurate.
double signed_volume(const meshing::TriMesh& mesh) {
  const Eigen::RowVector3d c = mesh.vertices.colwise().mean();
  double six_volume = 0;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3d a = (mesh.vertices.row(mesh.faces(f, 0)) - c).transpose();
    const Eigen::Vector3d b = (mesh.vertices.row(mesh.faces(f, 1)) - c).transpose();
    const Eigen::Vector3d d = (mesh.vertices.row(mesh.faces(f, 2)) - c).transpose();
    six_volume += a.dot(b.cross(d));
  }
  return six_volume / 6.0;
}

}  // namespace

// OFF and PLY headers declare element counts up front and assimp reserves memory for them before
// reading (invalid/OutOfMemory.off makes it reserve ~16 GB). Reject a header whose counts could
// not fit in the file: every vertex takes at least 6 bytes ("0 0 0\n"), every face at least 8.
void check_mesh_file_header(const std::string& file, const std::string& what) {
  std::ifstream in(file, std::ios::binary);
  std::string header(65536, '\0');
  in.read(header.data(), static_cast<std::streamsize>(header.size()));
  header.resize(static_cast<size_t>(in.gcount()));
  // gzip's magic bytes (trial 41, P9: a gzipped OBJ reached assimp, which said "OBJ: Invalid
  // face index.").
  if (header.starts_with("\x1f\x8b"))
    throw BodyError(what + " '" + file +
                    "' is gzip-compressed (it starts with gzip's bytes 1f 8b): unpack it first "
                    "(gunzip) and give the unpacked file");
  std::istringstream words(header);
  std::string word;
  double vertices = 0, faces = 0;
  if (!(words >> word)) return;
  if (word.size() >= 3 && word.compare(word.size() - 3, 3, "OFF") == 0) {
    // Skip comment and blank lines between the keyword and the counts. The first line that
    // opens with a number is the counts line, as assimp reads it, even without a face count
    // (a fuzz finding: "7777777777777777777777" alone on its line, which assimp wraps to 3.3e9
    // vertices and reserves 39 GB for, while a later line's "770" had passed this check).
    std::string line;
    while (std::getline(words, line)) {
      const auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream counts(line);
      if (!(counts >> vertices)) {
        vertices = 0;
        continue;
      }
      if (!(counts >> faces)) faces = 0;
      break;
    }
  } else if (word.size() >= 3 && std::tolower(static_cast<unsigned char>(word[0])) == 'p' &&
             std::tolower(static_cast<unsigned char>(word[1])) == 'l' &&
             std::tolower(static_cast<unsigned char>(word[2])) == 'y') {
    // assimp takes any file that starts with "ply", in any case ("Ply": a fuzz finding of
    // session 41), for PLY, whatever follows on the line (the third finding: "ply" and binary
    // bytes, no end_header, read for over 10 s).
    // assimp's PLY reader never returns on a header without end_header (found by
    // tests/fuzz/body_loader_fuzz): such a file is refused before it is read.
    if (header.find("end_header") == std::string::npos)
      throw BodyError(
          fmt::format("{} '{}' is corrupt: its PLY header has no end_header "
                      "line{}",
                      what, file, header.size() < 65536 ? "" : " in its first 64 KB"));
    // Nor on some header lines that hold numbers (the second finding: vertex data before
    // end_header). Free text lines stay allowed (Blender writes one), numbers do not.
    std::istringstream lines(header);
    std::string line;
    std::getline(lines, line);  // "ply"
    for (int number = 2; std::getline(lines, line); ++number) {
      std::istringstream first(line);
      std::string keyword;
      first >> keyword;
      if (keyword == "end_header") break;
      const bool numeric =
          !keyword.empty() && (std::isdigit(static_cast<unsigned char>(keyword[0])) ||
                               keyword[0] == '-' || keyword[0] == '+' || keyword[0] == '.');
      const bool binary = std::any_of(line.begin(), line.end(), [](char c) {
        return static_cast<unsigned char>(c) < 0x09 || static_cast<unsigned char>(c) == 0x7f;
      });
      if (numeric || binary)
        throw BodyError(
            fmt::format("{} '{}' is corrupt: line {} of its PLY header is not "
                        "a header line (it holds {} before end_header)",
                        what, file, number, numeric ? "numbers" : "binary bytes"));
    }
    // The keyword must open a line: inside another word ("floend_headerat32", a later fuzz
    // finding) it does not end the header, and assimp reads on for ever.
    const auto ends_header = [](const std::string& text) {
      std::istringstream rows(text);
      std::string row, keyword;
      while (std::getline(rows, row))
        if (std::istringstream(row) >> keyword && keyword == "end_header") return true;
      return false;
    };
    if (!ends_header(header))
      throw BodyError(
          fmt::format("{} '{}' is corrupt: its PLY header has no end_header line", what, file));
    while (words >> word && word != "end_header") {
      if (word != "element") continue;
      std::string kind;
      double count = 0;
      if (!(words >> kind >> count)) break;
      if (kind == "vertex") vertices = count;
      if (kind == "face") faces = count;
    }
  } else {
    return;
  }
  const double size = static_cast<double>(std::filesystem::file_size(file));
  if (vertices < 0 || faces < 0 || 6 * vertices + 8 * faces > size)
    throw BodyError(fmt::format(
        "{} '{}' is corrupt: its header declares {:.0f} vertices and {:.0f} faces, more "
        "than its {:.0f} bytes can hold",
        what, file, vertices, faces, size));
}

std::string AxisDirection::name() const {
  return std::string(sign > 0 ? "+" : "-") + "xyz"[axis];
}

AxisDirection AxisDirection::parse(const std::string& text) {
  std::string t;
  for (char c : text) t += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  AxisDirection d;
  size_t i = 0;
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) d.sign = t[i++] == '-' ? -1 : 1;
  if (t.size() != i + 1 || t[i] < 'x' || t[i] > 'z')
    throw BodyError("'" + text + "' is not an axis: use x, y or z with an optional + or -");
  d.axis = t[i] - 'x';
  return d;
}

std::vector<BodyHole> body_holes(const meshing::TriMesh& mesh) {
  // Directed edges; an edge whose reverse is absent and that appears once undirected is open.
  std::map<std::pair<int, int>, int> count;  // undirected edge → triangles using it
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<int> parent(static_cast<size_t>(mesh.vertices.rows()));
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int v) {
    while (parent[static_cast<size_t>(v)] != v)
      v = parent[static_cast<size_t>(v)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
    return v;
  };
  std::vector<std::pair<int, int>> open;
  for (const auto& [edge, n] : count)
    if (n == 1) {
      open.push_back(edge);
      parent[static_cast<size_t>(root(edge.first))] = root(edge.second);
    }
  std::map<int, std::set<int>> rims;  // root → rim vertices
  std::map<int, int> edges;
  for (const auto& [a, b] : open) {
    rims[root(a)].insert(a), rims[root(a)].insert(b);
    ++edges[root(a)];
  }
  std::vector<BodyHole> holes;
  for (const auto& [r, rim] : rims) {
    BodyHole hole;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
                    hi = -lo, sum = Eigen::Vector3d::Zero();
    for (const int v : rim) {
      const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
      sum += p, lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    }
    hole.centre = sum / static_cast<double>(rim.size());
    hole.across = (hi - lo).norm();
    hole.edges = edges[r];
    holes.push_back(hole);
  }
  std::sort(holes.begin(), holes.end(),
            [](const BodyHole& a, const BodyHole& b) { return a.across > b.across; });
  return holes;
}

const BodyHole* hole_near(const std::vector<BodyHole>& holes, const Eigen::Vector3d& p,
                          double margin) {
  const BodyHole* nearest = nullptr;
  double best = std::numeric_limits<double>::infinity();
  for (const BodyHole& hole : holes) {
    const double d = (p - hole.centre).norm();
    if (d <= 0.5 * hole.across + margin && d < best) best = d, nearest = &hole;
  }
  return nearest;
}

std::string builtin_body_path() {
  return kBuiltinPath;
}

namespace {

// A figure whose given "facing" (or "up", by its convention) turns it round is refused with the
// facing that would be right (trial 38: the built-in body with "facing": "+y" faced -Z, its
// landmarks were found on its back, and the first error was two curves 7 cm apart). Only for a
// standing figure: a body without landmarks (an obstacle, a figure turned sideways) is left as
// given.
void check_facing(const Body& body, const BodyOptions& options) {
  BodyLandmarks landmarks;
  try {
    landmarks = find_landmarks(body.mesh);
  } catch (const std::runtime_error&) {
    return;
  }
  const FacingCues cues = facing_cues(body.mesh, landmarks);
  if (!cues.backwards()) return;
  const RawBodyInfo& raw = body.raw;
  const AxisDirection right{raw.facing.axis, -raw.facing.sign};
  const AxisDirection convention =
      raw.up.axis == 2 ? AxisDirection{1, -raw.up.sign} : AxisDirection{2, 1};
  const std::string given =
      options.facing ? fmt::format("with \"facing\": \"{}\"", raw.facing.name())
                     : fmt::format("with \"up\": \"{}\" (whose convention faces the figure {})",
                                   raw.up.name(), raw.facing.name());
  std::string measured = fmt::format(
      "its head reaches {:.1f} cm out behind the neck and {:.1f} cm in front of it (a face "
      "reaches farther forward than the back of the head)",
      100 * cues.head.behind, 100 * cues.head.ahead);
  if (!cues.head.found) measured.clear();
  if (cues.feet.found)
    measured += fmt::format(
        "{}its feet {:.1f} cm behind the ankles and {:.1f} cm in front (toes reach farther "
        "than heels)",
        measured.empty() ? "" : ", ", 100 * cues.feet.behind, 100 * cues.feet.ahead);
  throw BodyFacingError(fmt::format(
      "{} the figure faces backwards: {}; give \"facing\": \"{}\"{}", given, measured, right.name(),
      right.axis == convention.axis && right.sign == convention.sign
          ? " (the convention for this up axis, so \"facing\" can also be left out)"
          : ""));
}

}  // namespace

Body load_body(const std::string& path, const BodyOptions& options) {
  const bool builtin = path == "builtin";
  const std::string file = builtin ? kBuiltinPath : path;
  if (builtin && !std::filesystem::exists(file))
    throw BodyError("the built-in body " + file +
                    " is missing: install the Debian package assimp-testmodels");
  Body body;
  meshing::TriMesh mesh = read_body_mesh(file, body);
  const meshing::TriMeshTopology topo = meshing::analyse_topology(mesh);
  if (!topo.edge_manifold())
    body.warnings.push_back(fmt::format(
        "{} edge(s) are shared by more than two triangles; collision may be unreliable there",
        topo.non_manifold_edges));
  if (!topo.oriented())
    body.warnings.push_back(
        fmt::format("{} edge(s) join triangles of opposite orientation; inside/outside tests may "
                    "be wrong there",
                    topo.inconsistent_edges));
  const size_t open_warning = body.warnings.size();
  if (topo.boundary_edges > 0)
    body.warnings.push_back(fmt::format(
        "the body is open ({} boundary edge(s)): collision treats the body as a closed surface, "
        "so cloth may fall through its holes or end on the wrong side near them",
        topo.boundary_edges));
  // A closed body whose faces point inward (the file's winding or handedness differs) would put
  // the cloth's contacts on the inside: its signed volume is negative. Flip it.
  body.raw.signed_volume = signed_volume(mesh);
  if (topo.closed() && topo.oriented() && body.raw.signed_volume < 0) {
    mesh.faces.col(1).swap(mesh.faces.col(2));
    body.raw.flipped_inside_out = true;
    body.warnings.push_back(
        "the body is inside out (its faces point inward: negative volume); its faces were "
        "flipped to point outward");
  }

  RawBodyInfo& raw = body.raw;
  raw.source = builtin ? "builtin (" + file + ")" : file;
  raw.box = meshing::bounding_box(mesh);
  const Eigen::Vector3d extent = raw.box.extent();
  // The axis a standing figure's height runs along by the rule below, for an inferred up and to
  // check a given one.
  const auto tallest_axis = [&] {
    for (int axis : {1, 2, 0})
      if (extent[axis] >= 0.99 * extent.maxCoeff()) return axis;
    return 0;
  };
  if (options.up) {
    raw.up = *options.up;
    raw.up_inferred = false;
    // A figure less than half as tall along the given up as along another axis lies on its side
    // (a Y-up file given "+z"): its height would be scaled from its depth, and the landmarks
    // then fail for want of a standing figure. Arms held out make a figure at most about as
    // wide as it is tall, so half leaves room for any pose. Only for a figure: a garment's body
    // (the proportions decide, whatever "height" or "scale" sets the size: trial 44 gave a Z-up
    // human "up": "+y" with its "height", and its depth was scaled to 1.66 m, a 6.4 m figure
    // lying face down that had landmarks), the built-in body, or a file without "height" or
    // "scale" whose height along the given up is no body's in m, cm or mm while along the
    // tallest axis it is one (a ground plane or a rod under a sheet, given "scale", is wide and
    // flat on purpose).
    const auto plausible = [](double h) {
      return (h >= 0.5 && h <= 2.5) || (h >= 50 && h <= 250) || (h >= 500 && h <= 2500);
    };
    const int tallest = tallest_axis();
    const bool figure =
        options.figure ||
        (!options.height && !options.scale &&
         (builtin || (!plausible(extent[raw.up.axis]) && plausible(extent[tallest]))));
    if (figure && tallest != raw.up.axis && extent[raw.up.axis] < 0.5 * extent[tallest]) {
      const char* names = "xyz";
      throw BodyUpError(fmt::format(
          "with \"up\": \"{}{}\" the body lies on its side: it is {:.4g} units along {} but "
          "{:.4g} along {}, and a standing figure is tallest along its up axis; is \"up\" "
          "right? The inferred up axis is +{}: give \"up\": \"+{}\" (\"-{}\" if the body "
          "then stands on its head), or leave \"up\" out",
          raw.up.sign > 0 ? '+' : '-', names[raw.up.axis], extent[raw.up.axis], names[raw.up.axis],
          extent[tallest], names[tallest], names[tallest], names[tallest], names[tallest]));
    }
  } else {
    // Rule: a standing figure is tallest along its up axis; the sign is taken as positive.
    // Extents within 1% of the largest are ties, settled in favour of y, then z (the two
    // conventions in use), then x.
    raw.up.axis = tallest_axis();
    raw.up.sign = 1;
  }
  // Facing follows the common convention of the up axis: Z-up files (Blender) face -Y,
  // Y-up files (glTF, OBJ) face +Z, X-up files face +Z.
  raw.facing = raw.up.axis == 2 ? AxisDirection{1, -raw.up.sign} : AxisDirection{2, 1};
  if (options.facing) {
    // Given (trial 37: a T-posed figure stood up with "up" then faced sideways, its arms along
    // the depth, and had no landmarks): across the up axis, or there is no such rotation.
    if (options.facing->axis == raw.up.axis)
      throw BodyFacingError(fmt::format(
          "\"facing\": \"{}\" runs along the up axis {}: a figure faces across its up axis; "
          "give one of the other two axes",
          options.facing->name(), raw.up.name()));
    raw.facing = *options.facing;
  }
  raw.height = extent[raw.up.axis];
  if (!(raw.height > 0)) throw BodyError("body file '" + file + "' is flat along its up axis");

  if (options.height && !(*options.height >= kMinBodyHeight && *options.height <= kMaxBodyHeight))
    throw BodyError(fmt::format("a body height of {} m is outside {} .. {} m", *options.height,
                                kMinBodyHeight, kMaxBodyHeight));
  if (options.scale && !(std::isfinite(*options.scale) && *options.scale > 0))
    throw BodyError(fmt::format(
        "a scale of {} metres per file unit is not a positive finite number", *options.scale));
  const double target = options.height.value_or(builtin ? kBuiltinHeight : 0.0);
  if (target > 0) {
    raw.scale = target / raw.height;
    raw.scale_rule = fmt::format("height {:.3f} m {}", target,
                                 options.height ? "given" : "of the built-in body");
  } else if (options.scale) {
    raw.scale = *options.scale;
    raw.scale_rule = "scale given";
  } else if (raw.height >= 0.5 && raw.height <= 2.5) {
    raw.scale = 1.0;
    raw.scale_rule = "height looks like metres";
  } else if (raw.height >= 50 && raw.height <= 250) {
    raw.scale = 0.01;
    raw.scale_rule = "height looks like centimetres";
    // 50-100 units is a short body in centimetres or a tall one in inches (a 67-inch body was
    // read as 0.67 m and every curve then missed it): say which was chosen and how to choose.
    if (raw.height < 100)
      body.warnings.push_back(fmt::format(
          "body height {:.4g} units was read as centimetres ({:.2f} m tall); if the file is in "
          "inches the body is {:.2f} m tall: give \"scale\": 0.0254 (or its \"height\")",
          raw.height, raw.height * 0.01, raw.height * 0.0254));
  } else if (raw.height >= 500 && raw.height <= 2500) {
    raw.scale = 0.001;
    raw.scale_rule = "height looks like millimetres";
  } else if (!(raw.height >= kMinGuessedHeight && raw.height <= kMaxGuessedHeight)) {
    // No unit makes such a file a figure (trial 41, P8: a human in units of 1e30 was quietly
    // made 1.75 m tall): a guess would hide a broken export.
    throw BodyError(fmt::format(
        "the body is {:.4g} file units tall, which no unit makes a body's size (metres, "
        "centimetres, millimetres, inches or even micrometres): the file's coordinates are "
        "probably broken; if it is right, give its \"height\" in metres or its \"scale\" in "
        "metres per file unit",
        raw.height));
  } else {
    raw.scale = kBuiltinHeight / raw.height;
    raw.scale_rule = fmt::format("unknown units: scaled to {:.2f} m", kBuiltinHeight);
    body.warnings.push_back(fmt::format(
        "body height {:.4g} is not plausible in m, cm or mm; scaled to {:.2f} m (give 'height' or "
        "'scale' to choose)",
        raw.height, kBuiltinHeight));
  }

  const double height_m = raw.height * raw.scale;
  if (!(height_m >= kMinBodyHeight && height_m <= kMaxBodyHeight))
    throw BodyError(fmt::format(
        "the body would be {:.4g} m tall ({:.4g} file units at {:.4g} m per unit), outside {} .. "
        "{} m: give a 'height' or a 'scale' that makes it a body's size",
        height_m, raw.height, raw.scale, kMinBodyHeight, kMaxBodyHeight));
  // Taller than any person: accepted (a scene's obstacle may be anything up to 5 m), but a
  // garment's body this tall is a unit mistake (trial 37: "scale": 0.0254 on a file in cm made a
  // 4.37 m figure, and the error came later as a curve that misses the body).
  if (height_m > kTallestPerson)
    body.warnings.push_back(fmt::format(
        "the body is {:.2f} m tall ({:.4g} file units at {:.4g} m per unit), taller than any "
        "person: if it is a figure, check its \"scale\" (0.01 for a file in centimetres, "
        "0.001 in millimetres, 0.0254 in inches) or give its \"height\"",
        height_m, raw.height, raw.scale));
  const Eigen::Matrix3d rotation = frame_rotation(raw.up, raw.facing);
  mesh.vertices = (mesh.vertices * rotation.transpose()) * raw.scale;
  const meshing::BoundingBox box = meshing::bounding_box(mesh);
  raw.shift = Eigen::Vector3d(-box.centre().x(), -box.min.y(), -box.centre().z());
  mesh.vertices.rowwise() += raw.shift.transpose();
  body.mesh = std::move(mesh);
  if (topo.boundary_edges > 0) {
    // Where the holes are, in the normalised frame the sketch's points use (trial 39, P6: a
    // scanned body with a hole under a curve was told only "34 boundary edge(s)").
    const std::vector<BodyHole> holes = body_holes(body.mesh);
    std::string where;
    constexpr size_t kShown = 3;
    for (size_t h = 0; h < std::min(holes.size(), kShown); ++h)
      where += fmt::format("{}{:.1f} cm across at ({:.3f}, {:.3f}, {:.3f}) m", h == 0 ? "" : "; ",
                           100 * holes[h].across, holes[h].centre.x(), holes[h].centre.y(),
                           holes[h].centre.z());
    if (holes.size() > kShown) where += fmt::format("; and {} more", holes.size() - kShown);
    body.warnings[open_warning] +=
        fmt::format("; {} {}: {}", holes.size(), holes.size() == 1 ? "hole" : "holes", where);
  }
  if (options.facing || options.up) check_facing(body, options);
  // Said once per process: a sketch whose points name landmarks loads its body while it is
  // read and again to mesh it, and the designer saw each repair twice.
  static std::mutex mutex;
  static std::set<std::string> said;
  const std::lock_guard lock(mutex);
  // Named by its file, as every other message is (trial 41, P8: "the body is inside out"
  // named no file).
  for (const auto& warning : body.warnings)
    if (said.insert(fmt::format("{}: {}", file, warning)).second)
      spdlog::warn("body file '{}': {}", file, warning);
  return body;
}

std::string upside_down_advice(const Body& body) {
  // Turned over about the facing axis (a proper rotation: still facing +Z), feet back on the
  // floor.
  meshing::TriMesh turned = body.mesh;
  turned.vertices.col(0) *= -1.0;
  turned.vertices.col(1) *= -1.0;
  turned.vertices.col(1).array() -= turned.vertices.col(1).minCoeff();
  try {
    find_landmarks(turned);
  } catch (const std::runtime_error&) {
    return "";
  }
  const AxisDirection down{body.raw.up.axis, -body.raw.up.sign};
  return fmt::format(
      "the figure looks upside down (it has landmarks once turned over): give "
      "\"up\": \"{}\"",
      down.name());
}

meshing::TriMesh load_body_pose(const std::string& path, const Body& rest) {
  Body scratch;
  meshing::TriMesh mesh = read_body_mesh(path, scratch);
  // The same mesh moved: the same triangles over the same vertices, or the poses cannot be
  // interpolated vertex by vertex.
  if (rest.raw.flipped_inside_out) mesh.faces.col(1).swap(mesh.faces.col(2));  // as the rest body
  const bool same_counts = mesh.vertex_count() == rest.mesh.vertex_count() &&
                           mesh.face_count() == rest.mesh.face_count();
  if (!same_counts || mesh.faces != rest.mesh.faces)
    throw BodyError(fmt::format(
        "'{}' is not the body's mesh moved: it has {} vertices and {} triangles, the "
        "body {} and {}{} (export every pose from the same rig, without remeshing)",
        path, mesh.vertex_count(), mesh.face_count(), rest.mesh.vertex_count(),
        rest.mesh.face_count(), same_counts ? ", but its triangles join other vertices" : ""));
  const RawBodyInfo& raw = rest.raw;
  mesh.vertices = (mesh.vertices * frame_rotation(raw.up, raw.facing).transpose()) * raw.scale;
  mesh.vertices.rowwise() += raw.shift.transpose();
  return mesh;
}

}  // namespace sd::garment
