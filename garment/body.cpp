#include "garment/body.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>

namespace sd::garment {
namespace {

constexpr const char* kBuiltinPath = "/usr/share/assimp/models/BLEND/HUMAN.blend";
constexpr double kBuiltinHeight = 1.75;

void collect_meshes(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                    std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>& faces,
                    Eigen::Index& mesh_count) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const int base = static_cast<int>(vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      faces.emplace_back(base + static_cast<int>(face.mIndices[0]),
                         base + static_cast<int>(face.mIndices[1]),
                         base + static_cast<int>(face.mIndices[2]));
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

}  // namespace

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

std::string builtin_body_path() { return kBuiltinPath; }

Body load_body(const std::string& path, const BodyOptions& options) {
  const bool builtin = path == "builtin";
  const std::string file = builtin ? kBuiltinPath : path;
  if (!std::filesystem::exists(file))
    throw BodyError(builtin ? "the built-in body " + file +
                                  " is missing: install the Debian package assimp-testmodels"
                            : "body file '" + file + "' does not exist");

  Assimp::Importer importer;
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                         aiProcess_SortByPType | aiProcess_FindInvalidData;
  const aiScene* scene = importer.ReadFile(file, flags);
  if (scene == nullptr)
    throw BodyError("cannot read body file '" + file + "': " + importer.GetErrorString());
  if (scene->mRootNode == nullptr || scene->mNumMeshes == 0)
    throw BodyError("body file '" + file + "' holds no mesh");

  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> tris;
  Body body;
  collect_meshes(*scene, *scene->mRootNode, aiMatrix4x4(), points, tris, body.raw.meshes);
  if (tris.empty()) throw BodyError("body file '" + file + "' holds no triangles");
  for (const auto& p : points)
    if (!p.allFinite())
      throw BodyError("body file '" + file + "' has NaN or infinite vertex coordinates");

  meshing::TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) mesh.vertices.row(i) = points[i].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) mesh.faces.row(i) = tris[i].transpose();

  RawBodyInfo& raw = body.raw;
  raw.source = builtin ? "builtin (" + file + ")" : file;
  raw.box = meshing::bounding_box(mesh);
  const Eigen::Vector3d extent = raw.box.extent();
  if (options.up) {
    raw.up = *options.up;
    raw.up_inferred = false;
  } else {
    // Rule: a standing figure is tallest along its up axis; the sign is taken as positive.
    extent.maxCoeff(&raw.up.axis);
    raw.up.sign = 1;
  }
  // Facing follows the common convention of the up axis: Z-up files (Blender) face -Y,
  // Y-up files (glTF, OBJ) face +Z, X-up files face +Z.
  raw.facing = raw.up.axis == 2 ? AxisDirection{1, -raw.up.sign} : AxisDirection{2, 1};
  raw.height = extent[raw.up.axis];
  if (!(raw.height > 0)) throw BodyError("body file '" + file + "' is flat along its up axis");

  const double target = options.height.value_or(builtin ? kBuiltinHeight : 0.0);
  if (target > 0) {
    raw.scale = target / raw.height;
    raw.scale_rule = fmt::format("height {:.3f} m {}", target, options.height ? "given" : "of the built-in body");
  } else if (options.scale) {
    raw.scale = *options.scale;
    raw.scale_rule = "scale given";
  } else if (raw.height >= 0.5 && raw.height <= 2.5) {
    raw.scale = 1.0;
    raw.scale_rule = "height looks like metres";
  } else if (raw.height >= 50 && raw.height <= 250) {
    raw.scale = 0.01;
    raw.scale_rule = "height looks like centimetres";
  } else if (raw.height >= 500 && raw.height <= 2500) {
    raw.scale = 0.001;
    raw.scale_rule = "height looks like millimetres";
  } else {
    raw.scale = kBuiltinHeight / raw.height;
    raw.scale_rule = fmt::format("unknown units: scaled to {:.2f} m", kBuiltinHeight);
    body.warnings.push_back(fmt::format(
        "body height {:.4g} is not plausible in m, cm or mm; scaled to {:.2f} m (give 'height' or "
        "'scale' to choose)", raw.height, kBuiltinHeight));
  }

  const Eigen::Matrix3d rotation = frame_rotation(raw.up, raw.facing);
  mesh.vertices = (mesh.vertices * rotation.transpose()) * raw.scale;
  const meshing::BoundingBox box = meshing::bounding_box(mesh);
  const Eigen::RowVector3d shift(-box.centre().x(), -box.min.y(), -box.centre().z());
  mesh.vertices.rowwise() += shift;
  body.mesh = std::move(mesh);
  for (const auto& warning : body.warnings) spdlog::warn("{}", warning);
  return body;
}

}  // namespace sd::garment
