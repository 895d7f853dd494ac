#include "geometry/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <memory>
#include <unordered_map>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <Eigen/Geometry>

#include "core/error.h"

namespace spec2fab {

namespace {

// Hashes the exact bits of a position (with -0 folded onto +0) so that welding
// joins only identical coordinates.
struct PositionKey {
  std::uint64_t bits[3];
  explicit PositionKey(const Vec3& p) {
    for (int k = 0; k < 3; ++k) bits[k] = std::bit_cast<std::uint64_t>(p[k] + 0.0);
  }
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct PositionKeyHash {
  size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint64_t b : k.bits) h = (h ^ b) * 0xff51afd7ed558ccdull, h ^= h >> 32;
    return static_cast<size_t>(h);
  }
};

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& verb,
                       const std::string& reason) {
  throw InputError(file.string() + ": cannot " + verb + " mesh: " + reason);
}

std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  return text.empty() ? std::string("unknown error") : text;
}

struct SceneWalker {
  const aiScene* scene;
  double scale;
  Mesh* mesh;
  std::unordered_map<PositionKey, int, PositionKeyHash> index_of;
  bool all_have_uv = true;

  int weld(const Vec3& p) {
    auto [it, inserted] =
        index_of.try_emplace(PositionKey(p), static_cast<int>(mesh->vertices.size()));
    if (inserted) mesh->vertices.push_back(p);
    return it->second;
  }

  void add(const aiMesh& m, const aiMatrix4x4& world) {
    const bool has_uv = m.HasTextureCoords(0);
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
      const aiFace& face = m.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left over by triangulation
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        const aiVector3D& v = m.mVertices[face.mIndices[k]];
        Vec3 p;
        for (int r = 0; r < 3; ++r)
          p[r] = (double(world[r][0]) * v.x + double(world[r][1]) * v.y +
                  double(world[r][2]) * v.z + double(world[r][3])) *
                 scale;
        tri[k] = weld(p);
        if (has_uv) {
          const aiVector3D& uv = m.mTextureCoords[0][face.mIndices[k]];
          mesh->corner_uv.emplace_back(uv.x, uv.y);
        }
      }
      if (!has_uv) all_have_uv = false;
      mesh->triangles.push_back(tri);
    }
  }

  void walk(const aiNode& node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 world = parent * node.mTransformation;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) add(*scene->mMeshes[node.mMeshes[i]], world);
    for (unsigned i = 0; i < node.mNumChildren; ++i) walk(*node.mChildren[i], world);
  }
};

}  // namespace

Mesh load_mesh(const std::filesystem::path& file, double scale_to_mm) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) fail(file, "read", "file not found");
  if (!std::filesystem::is_regular_file(file, error)) fail(file, "read", "not a regular file");
  if (!(scale_to_mm > 0)) fail(file, "read", "scale to mm must be positive");

  // No DefaultLogger is created, so Assimp stays silent (its NullLogger).
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(file.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr) fail(file, "read", one_line(importer.GetErrorString()));
  if (scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    fail(file, "read", "no triangles");

  Mesh mesh;
  mesh.name = file.filename().string();
  SceneWalker walker{scene, scale_to_mm, &mesh, {}, true};
  walker.walk(*scene->mRootNode, aiMatrix4x4());
  if (mesh.triangles.empty()) fail(file, "read", "no triangles");
  if (!walker.all_have_uv) mesh.corner_uv.clear();
  return mesh;
}

namespace {

// Splits vertices only where corner uvs differ (Assimp stores uvs per vertex).
std::unique_ptr<aiMesh> make_indexed_mesh(const Mesh& mesh) {
  std::vector<Vec3> positions;
  std::vector<Vec2> uvs;
  std::vector<int> corner_index(3 * mesh.triangles.size());
  if (mesh.has_uv()) {
    struct Key {
      int vertex;
      std::uint64_t u, v;
      bool operator==(const Key&) const = default;
    };
    struct KeyHash {
      size_t operator()(const Key& k) const {
        return std::hash<std::uint64_t>()(k.u * 31 + k.v) ^
               (size_t(k.vertex) * 0x9e3779b97f4a7c15ull);
      }
    };
    std::unordered_map<Key, int, KeyHash> index_of;
    for (size_t c = 0; c < corner_index.size(); ++c) {
      const int v = mesh.triangles[c / 3][c % 3];
      const Vec2& uv = mesh.corner_uv[c];
      const Key key{v, std::bit_cast<std::uint64_t>(uv.x()), std::bit_cast<std::uint64_t>(uv.y())};
      auto [it, inserted] = index_of.try_emplace(key, static_cast<int>(positions.size()));
      if (inserted) {
        positions.push_back(mesh.vertices[v]);
        uvs.push_back(uv);
      }
      corner_index[c] = it->second;
    }
  } else {
    positions = mesh.vertices;
    for (size_t c = 0; c < corner_index.size(); ++c) corner_index[c] = mesh.triangles[c / 3][c % 3];
  }

  auto out = std::make_unique<aiMesh>();
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned>(positions.size());
  out->mVertices = new aiVector3D[positions.size()];
  for (size_t i = 0; i < positions.size(); ++i)
    out->mVertices[i] =
        aiVector3D(ai_real(positions[i].x()), ai_real(positions[i].y()), ai_real(positions[i].z()));
  if (!uvs.empty()) {
    out->mNumUVComponents[0] = 2;
    out->mTextureCoords[0] = new aiVector3D[uvs.size()];
    for (size_t i = 0; i < uvs.size(); ++i)
      out->mTextureCoords[0][i] = aiVector3D(ai_real(uvs[i].x()), ai_real(uvs[i].y()), 0);
  }
  out->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    aiFace& face = out->mFaces[t];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned>(corner_index[3 * t + k]);
  }
  return out;
}

// One vertex per corner with the face normal: STL stores a normal per facet,
// and Assimp's STL writer averages the vertex normals of each facet.
std::unique_ptr<aiMesh> make_facet_mesh(const Mesh& mesh) {
  auto out = std::make_unique<aiMesh>();
  const size_t n = 3 * mesh.triangles.size();
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned>(n);
  out->mVertices = new aiVector3D[n];
  out->mNormals = new aiVector3D[n];
  out->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 normal = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                            .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                            .normalized();
    aiFace& face = out->mFaces[t];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.vertices[tri[k]];
      out->mVertices[3 * t + k] = aiVector3D(ai_real(p.x()), ai_real(p.y()), ai_real(p.z()));
      out->mNormals[3 * t + k] =
          aiVector3D(ai_real(normal.x()), ai_real(normal.y()), ai_real(normal.z()));
      face.mIndices[k] = static_cast<unsigned>(3 * t + k);
    }
  }
  return out;
}

}  // namespace

void save_mesh(const Mesh& mesh, const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const char* format = extension == ".obj"   ? "objnomtl"
                       : extension == ".stl" ? "stlb"
                       : extension == ".ply" ? "ply"
                                             : nullptr;
  if (format == nullptr) fail(file, "write", "unknown extension (expected .obj, .stl or .ply)");
  if (mesh.triangles.empty()) fail(file, "write", "no triangles");

  aiScene scene;
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh*[1];
  scene.mMeshes[0] =
      (extension == ".stl" ? make_facet_mesh(mesh) : make_indexed_mesh(mesh)).release();
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1];
  scene.mMaterials[0] = new aiMaterial();
  scene.mRootNode = new aiNode();
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};

  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, file.string()) != aiReturn_SUCCESS)
    fail(file, "write", one_line(exporter.GetErrorString()));
}

}  // namespace spec2fab
