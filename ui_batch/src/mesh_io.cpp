#include "vproto/ui_batch/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <vector>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {

geometry::TriMesh read_mesh(const std::string& path) {
  Assimp::Importer importer;
  // only geometry matters: drop normals and other attributes so welding is by position
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS | aiComponent_MATERIALS);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene)
    throw InputError(SourceLoc{path, 0, 0},
                     std::string("cannot read mesh: ") + importer.GetErrorString());
  std::vector<Eigen::Vector3d> verts;
  std::vector<Eigen::Vector3i> tris;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const int base = static_cast<int>(verts.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v)
      verts.emplace_back(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      tris.emplace_back(base + static_cast<int>(face.mIndices[0]),
                        base + static_cast<int>(face.mIndices[1]),
                        base + static_cast<int>(face.mIndices[2]));
    }
  }
  if (tris.empty()) throw InputError(SourceLoc{path, 0, 0}, "the file holds no triangles");
  geometry::TriMesh out;
  out.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (std::size_t i = 0; i < verts.size(); ++i)
    out.V.row(static_cast<Eigen::Index>(i)) = verts[i].transpose();
  out.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t i = 0; i < tris.size(); ++i)
    out.F.row(static_cast<Eigen::Index>(i)) = tris[i].transpose();
  return out;
}

void write_mesh(const geometry::TriMesh& mesh, const std::string& name, MeshFormat format,
                const std::string& path) {
  // one mesh in one node; assimp owns and frees everything reachable from the scene
  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mRootNode->mName = aiString(name);
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMaterials = 1;
  scene.mMeshes = new aiMesh* [1] { new aiMesh() };
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  aiMesh* m = scene.mMeshes[0];
  m->mName = aiString(name);
  m->mMaterialIndex = 0;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mNumVertices = static_cast<unsigned>(mesh.V.rows());
  m->mVertices = new aiVector3D[m->mNumVertices];
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
    m->mVertices[i] =
        aiVector3D(static_cast<ai_real>(mesh.V(i, 0)), static_cast<ai_real>(mesh.V(i, 1)),
                   static_cast<ai_real>(mesh.V(i, 2)));
  m->mNumFaces = static_cast<unsigned>(mesh.F.rows());
  m->mFaces = new aiFace[m->mNumFaces];
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    aiFace& face = m->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices =
        new unsigned[3]{static_cast<unsigned>(mesh.F(f, 0)), static_cast<unsigned>(mesh.F(f, 1)),
                        static_cast<unsigned>(mesh.F(f, 2))};
  }
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    Assimp::Exporter exporter;
    const char* id = format == MeshFormat::kStl ? "stlb" : "objnomtl";
    if (exporter.Export(&scene, id, tmp.string()) != AI_SUCCESS)
      throw InputError("cannot write '" + path + "': " + exporter.GetErrorString());
  });
}

}  // namespace vproto::ui_batch
