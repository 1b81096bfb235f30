#include "src/app/pipeline/mesh_export.hpp"

#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>

namespace sd::app {
namespace {

// Two unit quads side by side, one per group.
ExportMesh two_panels() {
  ExportMesh m;
  m.vertices.resize(6, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0;
  m.faces.resize(2, 4);
  m.faces << 0, 1, 4, 3, 1, 2, 5, 4;
  m.face_groups = {0, 1};
  m.group_names = {"front", "back"};
  return m;
}

TEST(MeshExport, ObjHasGroupsAndOneBasedQuads) {
  const std::string obj = to_obj(two_panels(), "garment");
  EXPECT_NE(obj.find("o garment\n"), std::string::npos);
  EXPECT_NE(obj.find("g front\nf 1 2 5 4\n"), std::string::npos) << obj;
  EXPECT_NE(obj.find("g back\nf 2 3 6 5\n"), std::string::npos) << obj;
}

TEST(MeshExport, GlbReimportsWithSameGeometry) {
  const std::string glb = to_glb(two_panels(), "garment");
  ASSERT_GT(glb.size(), 100u);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFileFromMemory(glb.data(), glb.size(), 0, "glb");
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 2u);
  double area = 0;
  unsigned triangles = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      ASSERT_EQ(face.mNumIndices, 3u);
      const aiVector3D a = mesh.mVertices[face.mIndices[0]], b = mesh.mVertices[face.mIndices[1]],
                       c = mesh.mVertices[face.mIndices[2]];
      const aiVector3D n = (b - a) ^ (c - a);
      EXPECT_GT(n.z, 0) << "winding kept (normal +z)";
      area += 0.5 * n.Length();
      ++triangles;
    }
  }
  EXPECT_EQ(triangles, 4u);
  EXPECT_NEAR(area, 2.0, 1e-6);
}

}  // namespace
}  // namespace sd::app
