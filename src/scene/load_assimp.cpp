// Every format without an own loader (glTF/GLB, 3DS, DAE, FBX, ...) through assimp: polygons
// kept as polygons, node transforms flattened in double, one mesh range per mesh instance.
// Produces an unfinalized Scene for loadScene() (load.cpp); behaviour in docs/loaders.md.
#include <assimp/GltfMaterial.h>
#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "scene/loaders.hpp"

// Debian's assimp is built with its internal assertions on, and its handler aborts the process:
// a malformed glTF could kill the program. This definition takes the place of the library's (the
// program's own symbol is found first) and throws instead, which Importer::ReadFile reports as a
// failed import, so the file is refused with one line like any other bad input.
namespace Assimp {
void aiAssertViolation(const char* expression, const char* file, int line) {
  throw std::runtime_error("an internal check of assimp failed (" + std::string(expression) + " at " + file + ":" +
                           std::to_string(line) + ")");
}
}  // namespace Assimp

namespace hsr::loaders {
namespace {

/// assimp's row-major float matrix as a glm (column-major) double matrix.
dmat4 toDmat4(const aiMatrix4x4& m) {
  const ai_real* rows[4] = {m[0], m[1], m[2], m[3]};
  dmat4 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out[c][r] = double(rows[r][c]);
  return out;
}

/// A material's colour: glTF's base colour factor or the classic diffuse colour, with its
/// alpha times the opacity (as glTF's alphaMode says). assimp's stand-in material (formats without any) is the default grey.
Rgba8 materialColor(const aiMaterial* material) {
  if (!material) return kDefaultColor;
  aiString name;
  if (material->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && std::strcmp(name.C_Str(), AI_DEFAULT_MATERIAL_NAME) == 0)
    return kDefaultColor;
  aiColor4D color;
  if (material->Get(AI_MATKEY_BASE_COLOR, color) != AI_SUCCESS &&
      material->Get(AI_MATKEY_COLOR_DIFFUSE, color) != AI_SUCCESS)
    return kDefaultColor;
  float opacity = 1;
  material->Get(AI_MATKEY_OPACITY, opacity);
  double alpha = double(color.a) * opacity;
  // glTF (its materials carry alphaMode): the base colour's alpha alone (assimp also copies it into
  // the opacity); OPAQUE (the default) ignores it; MASK is opaque from alphaCutoff (0.5) up, else
  // fully transparent; BLEND blends.
  aiString mode;
  if (material->Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS) {
    alpha = color.a;
    float cutoff = 0.5f;
    material->Get(AI_MATKEY_GLTF_ALPHACUTOFF, cutoff);
    if (std::strcmp(mode.C_Str(), "OPAQUE") == 0) alpha = 1;
    if (std::strcmp(mode.C_Str(), "MASK") == 0) alpha = alpha >= cutoff ? 1 : 0;
  }
  return Rgba8{unitToByte(color.r), unitToByte(color.g), unitToByte(color.b), unitToByte(alpha)};
}

class AssimpReader {
 public:
  AssimpReader(const std::string& path, const aiScene& ai) : path_(path), ai_(ai) { scene_.source = path; }

  Scene run() {
    // Pre-order walk of the node tree (a node's meshes, then its children in order) with an
    // explicit stack: file order without recursion depth limits.
    struct Pending {
      const aiNode* node;
      dmat4 worldFromParent;
    };
    std::vector<Pending> stack{{ai_.mRootNode, dmat4(1.0)}};
    while (!stack.empty()) {
      auto [node, worldFromParent] = stack.back();
      stack.pop_back();
      const dmat4 worldFromNode = worldFromParent * toDmat4(node->mTransformation);
      for (unsigned k = 0; k < node->mNumMeshes; ++k) {
        if (node->mMeshes[k] >= ai_.mNumMeshes) throw InputError(path_ + ": assimp: node refers to a missing mesh");
        addMesh(*ai_.mMeshes[node->mMeshes[k]], worldFromNode, node->mName.C_Str());
      }
      for (unsigned c = node->mNumChildren; c-- > 0;) stack.push_back({node->mChildren[c], worldFromNode});
    }
    if (skippedPrimitives_)
      scene_.problems.notes.push_back(path_ + ": " + std::to_string(skippedPrimitives_) +
                                      " point/line primitives skipped (only polygons are drawn)");
    return std::move(scene_);
  }

 private:
  void addMesh(const aiMesh& mesh, const dmat4& worldFromMesh, const char* nodeName) {
    if (scene_.positions.size() + mesh.mNumVertices > std::numeric_limits<uint32_t>::max())
      throw InputError(path_ + ": more than 2^32 vertices");
    scene_.beginMesh(mesh.mName.length ? mesh.mName.C_Str() : nodeName);
    const uint32_t base = uint32_t(scene_.positions.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      scene_.positions.push_back(dvec3(worldFromMesh * dvec4(p.x, p.y, p.z, 1.0)));
    }
    // Colour: the mean of the face's vertex colours when the mesh has them, else the material's.
    const Rgba8 material = mesh.mMaterialIndex < ai_.mNumMaterials ? materialColor(ai_.mMaterials[mesh.mMaterialIndex])
                                                                   : kDefaultColor;
    const aiColor4D* vertexColors = mesh.mColors[0];
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices < 3) {
        ++skippedPrimitives_;
        continue;
      }
      indices_.clear();
      aiColor4D sum(0, 0, 0, 0);
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        unsigned i = face.mIndices[k];
        if (i >= mesh.mNumVertices) throw InputError(path_ + ": assimp: face index out of range");
        indices_.push_back(base + i);
        if (vertexColors) sum = sum + vertexColors[i];
      }
      Rgba8 color = material;
      if (vertexColors) {
        float n = float(face.mNumIndices);
        color = Rgba8{unitToByte(sum.r / n), unitToByte(sum.g / n), unitToByte(sum.b / n), unitToByte(sum.a / n)};
      }
      scene_.addFace(indices_, color);
    }
  }

  const std::string& path_;
  const aiScene& ai_;
  Scene scene_;
  std::vector<uint32_t> indices_;
  uint64_t skippedPrimitives_ = 0;
};

/// A binary glTF (GLB) declares its first chunk's length in its header (bytes 12-15, glTF 1 and
/// 2); assimp allocates that much before reading. A length beyond the file is refused here instead
/// (a 3 KB file declaring a 1.7 GB chunk took assimp 1.7 GB and seconds).
void checkGlbHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[20];
  if (!in.read(reinterpret_cast<char*>(h), sizeof h) || std::memcmp(h, "glTF", 4) != 0) return;
  const uint64_t first = uint32_t(h[12]) | uint32_t(h[13]) << 8 | uint32_t(h[14]) << 16 | uint32_t(h[15]) << 24;
  const uint64_t fileSize = std::filesystem::file_size(path);
  if (first > fileSize - sizeof h)
    throw InputError(path + ": GLB header: the first chunk declares " + std::to_string(first) +
                     " bytes, more than the file's " + std::to_string(fileSize) + " hold");
}

constexpr unsigned kImportFlags = aiProcess_ValidateDataStructure;

// In the probing child: a crash ends it by its signal, without a core file and without the
// handlers a sanitizer or fuzzer installed (which would report assimp's crash as hsr's).
void dieQuietlyOnCrash() {
  const rlimit noCore{0, 0};
  setrlimit(RLIMIT_CORE, &noCore);
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(sig, SIG_DFL);
}

/// Debian's assimp dereferences null on some malformed files (a glTF line loop whose indices lie
/// beyond its vertices, found by fuzzing): the import is tried first in a forked child, and a
/// child that does not end normally makes the file refused instead of the program killed. The child
/// only imports and leaves with _exit, so nothing of the parent's state runs twice.
void checkAssimpSurvives(const std::string& path) {
  const pid_t child = fork();
  if (child < 0) return;  // no process to spare: import in-process, as without the check
  if (child == 0) {
    dieQuietlyOnCrash();
    try {
      Assimp::Importer importer;
      importer.ReadFile(path, kImportFlags);
    } catch (...) {
    }
    _exit(0);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0)
    if (errno != EINTR) return;
  // A sanitizer that catches a bad access before it faults ends the child with a status instead.
  if (WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) != 0))
    throw InputError(path + ": assimp crashed reading the file (" +
                     (WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                          : "exit status " + std::to_string(WEXITSTATUS(status))) +
                     "): it is malformed in a way assimp does not check");
}

}  // namespace

Scene loadAssimp(const std::string& path) {
  checkGlbHeader(path);
  checkAssimpSurvives(path);
  Assimp::Importer importer;
  // No triangulation or vertex welding: faces stay the file's polygons, in the file's order.
  // The validation step turns malformed files into an error rather than bad indices.
  const aiScene* ai = importer.ReadFile(path, kImportFlags);
  if (!ai) {
    std::string message = importer.GetErrorString();
    std::replace(message.begin(), message.end(), '\n', ' ');  // messages are one line
    throw InputError(path + ": assimp: " + message);
  }
  if (!ai->mRootNode) throw InputError(path + ": assimp: the file has no scene graph");
  return AssimpReader(path, *ai).run();
}

}  // namespace hsr::loaders
