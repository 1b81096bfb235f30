#include "src/app/pipeline/mesh_export.hpp"

#include <assimp/material.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <assimp/Exporter.hpp>
#include <memory>
#include <stdexcept>

#include "meshing/tri_mesh.hpp"
#include "src/render/scene.hpp"

namespace sd::app {
namespace {

int group_of(const ExportMesh& mesh, Eigen::Index face) {
  return mesh.face_groups.empty() ? 0 : mesh.face_groups[static_cast<size_t>(face)];
}

int group_count(const ExportMesh& mesh) {
  return std::max<int>(1, static_cast<int>(mesh.group_names.size()));
}

std::string group_name(const ExportMesh& mesh, int group) {
  return mesh.group_names.empty() ? "garment" : mesh.group_names[static_cast<size_t>(group)];
}

// Triangles of face f: one for a triangle, two for a quad (split along the shorter diagonal).
std::vector<Eigen::Vector3i> triangles_of(const ExportMesh& mesh, Eigen::Index f) {
  const auto& face = mesh.faces;
  if (face.cols() == 3) return {Eigen::Vector3i(face(f, 0), face(f, 1), face(f, 2))};
  const auto p = [&](int k) { return mesh.vertices.row(face(f, k)); };
  if ((p(0) - p(2)).squaredNorm() <= (p(1) - p(3)).squaredNorm())
    return {{face(f, 0), face(f, 1), face(f, 2)}, {face(f, 0), face(f, 2), face(f, 3)}};
  return {{face(f, 0), face(f, 1), face(f, 3)}, {face(f, 1), face(f, 2), face(f, 3)}};
}

}  // namespace

std::string to_obj(const ExportMesh& mesh, const std::string& object_name) {
  std::string out = fmt::format("# sketchdrape: {} vertices, {} faces\no {}\n",
                                mesh.vertices.rows(), mesh.faces.rows(), object_name);
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    out += fmt::format("v {:.9g} {:.9g} {:.9g}\n", mesh.vertices(v, 0), mesh.vertices(v, 1),
                       mesh.vertices(v, 2));
  for (int g = 0; g < group_count(mesh); ++g) {
    out += "g " + group_name(mesh, g) + "\n";
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
      if (group_of(mesh, f) != g) continue;
      out += "f";
      for (Eigen::Index k = 0; k < mesh.faces.cols(); ++k)
        out += fmt::format(" {}", mesh.faces(f, k) + 1);
      out += "\n";
    }
  }
  return out;
}

std::string to_glb(const ExportMesh& mesh, const std::string& object_name) {
  const int groups = group_count(mesh);
  // aiScene's destructor frees every array below with delete[], so they are allocated with new[].
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode(object_name);
  scene->mNumMeshes = static_cast<unsigned>(groups);
  scene->mMeshes = new aiMesh*[groups];
  scene->mNumMaterials = static_cast<unsigned>(groups);
  scene->mMaterials = new aiMaterial*[groups];
  scene->mRootNode->mNumMeshes = static_cast<unsigned>(groups);
  scene->mRootNode->mMeshes = new unsigned[groups];

  meshing::TriMesh tri;  // for smooth normals over the whole garment (seams stay smooth)
  std::vector<Eigen::Vector3i> all;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (const auto& t : triangles_of(mesh, f)) all.push_back(t);
  tri.vertices = mesh.vertices;
  tri.faces.resize(static_cast<Eigen::Index>(all.size()), 3);
  for (size_t i = 0; i < all.size(); ++i) tri.faces.row(static_cast<Eigen::Index>(i)) = all[i];
  const Eigen::MatrixX3d normals = meshing::vertex_normals(tri);
  // The previews' colours: groups sewn together in different colours (render::panel_colours).
  std::vector<int> slots;
  if (!mesh.face_groups.empty())
    slots = render::panel_palette_slots(
        Eigen::Map<const Eigen::VectorXi>(mesh.face_groups.data(),
                                          static_cast<Eigen::Index>(mesh.face_groups.size())),
        mesh.faces);

  for (int g = 0; g < groups; ++g) {
    std::vector<Eigen::Vector3i> triangles;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
      if (group_of(mesh, f) == g)
        for (const auto& t : triangles_of(mesh, f)) triangles.push_back(t);
    // Each group gets its own compact vertex array (glTF meshes do not share vertices).
    std::vector<int> local(static_cast<size_t>(mesh.vertices.rows()), -1);
    std::vector<int> used;
    for (const auto& t : triangles)
      for (int k = 0; k < 3; ++k)
        if (local[t[k]] < 0) {
          local[t[k]] = static_cast<int>(used.size());
          used.push_back(t[k]);
        }
    auto* m = new aiMesh();
    m->mName = group_name(mesh, g);
    m->mMaterialIndex = static_cast<unsigned>(g);
    m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m->mNumVertices = static_cast<unsigned>(used.size());
    m->mVertices = new aiVector3D[used.size()];
    m->mNormals = new aiVector3D[used.size()];
    for (size_t i = 0; i < used.size(); ++i) {
      const auto p = mesh.vertices.row(used[i]);
      const auto n = normals.row(used[i]);
      m->mVertices[i] = aiVector3D(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(p.z()));
      m->mNormals[i] = aiVector3D(static_cast<float>(n.x()), static_cast<float>(n.y()),
                                  static_cast<float>(n.z()));
    }
    m->mNumFaces = static_cast<unsigned>(triangles.size());
    m->mFaces = new aiFace[triangles.size()];
    for (size_t i = 0; i < triangles.size(); ++i) {
      aiFace& face = m->mFaces[i];
      face.mNumIndices = 3;
      face.mIndices = new unsigned[3];
      for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned>(local[triangles[i][k]]);
    }
    scene->mMeshes[g] = m;
    scene->mRootNode->mMeshes[g] = static_cast<unsigned>(g);

    auto* material = new aiMaterial();
    const aiString name(group_name(mesh, g));
    material->AddProperty(&name, AI_MATKEY_NAME);
    const Eigen::Vector3f c = render::panel_palette_colour(
        static_cast<size_t>(g) < slots.size() ? slots[static_cast<size_t>(g)] : g);
    const aiColor4D colour(c.x(), c.y(), c.z(), 1.0f);
    material->AddProperty(&colour, 1, AI_MATKEY_COLOR_DIFFUSE);
    material->AddProperty(&colour, 1, AI_MATKEY_BASE_COLOR);
    const int two_sided = 1;
    material->AddProperty(&two_sided, 1, AI_MATKEY_TWOSIDED);
    scene->mMaterials[g] = material;
  }

  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), "glb2");
  if (blob == nullptr)
    throw std::runtime_error(std::string("glTF export failed: ") + exporter.GetErrorString());
  return {static_cast<const char*>(blob->data), blob->size};
}

}  // namespace sd::app
