// load_mesh through assimp, confined to the file's own bytes (see mesh.hpp).
#include <assimp/BaseImporter.h>
#include <assimp/importerdesc.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "scene/mesh.hpp"
#include "scene/mesh_checks.hpp"

namespace scatter {

namespace {

// One file's bytes as an assimp stream.
class BytesStream : public Assimp::IOStream {
 public:
  explicit BytesStream(std::string_view bytes) : bytes_(bytes) {}
  size_t Read(void* out, size_t size, size_t count) override {
    if (size == 0) return 0;
    size_t n = std::min(count, (bytes_.size() - pos_) / size);
    std::memcpy(out, bytes_.data() + pos_, n * size);
    pos_ += n * size;
    return n;
  }
  size_t Write(const void*, size_t, size_t) override { return 0; }
  aiReturn Seek(size_t offset, aiOrigin origin) override {
    size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? pos_ : bytes_.size();
    if (origin == aiOrigin_END ? offset > bytes_.size() : offset > bytes_.size() - base)
      return aiReturn_FAILURE;
    pos_ = origin == aiOrigin_END ? bytes_.size() - offset : base + offset;
    return aiReturn_SUCCESS;
  }
  size_t Tell() const override { return pos_; }
  size_t FileSize() const override { return bytes_.size(); }
  void Flush() override {}

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
};

// Serves the one file being imported and nothing else: an importer that follows a reference
// (an OBJ's mtllib, a glTF's buffer uri) finds no such file, so an upload cannot make the daemon
// open /etc/passwd or block on a FIFO.
class OneFileIOSystem : public Assimp::IOSystem {
 public:
  OneFileIOSystem(std::string name, std::string_view bytes)
      : name_(std::move(name)), bytes_(bytes) {}
  bool Exists(const char* file) const override { return file && name_ == file; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!Exists(file) || !mode ||
        std::string_view(mode).find_first_of("wa+") != std::string_view::npos)
      return nullptr;
    return new BytesStream(bytes_);
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  std::string name_;
  std::string_view bytes_;
};

bool lists_extension(const char* list, std::string_view ext) {
  std::string_view l = list ? list : "";
  for (size_t at = 0; at < l.size();) {
    size_t end = l.find(' ', at);
    if (end == std::string_view::npos) end = l.size();
    if (l.substr(at, end - at) == ext) return true;
    at = end + 1;
  }
  return false;
}

// Only the importers of this extension may read the file: assimp otherwise offers bytes that no
// importer claims to every other importer by signature.
void keep_importers_of(Assimp::Importer& importer, const std::string& ext) {
  for (size_t i = importer.GetImporterCount(); i-- > 0;) {
    const aiImporterDesc* info = importer.GetImporterInfo(i);
    if (info && lists_extension(info->mFileExtensions, ext)) continue;
    Assimp::BaseImporter* loader = importer.GetImporter(i);
    if (importer.UnregisterLoader(loader) == aiReturn_SUCCESS)
      delete loader;  // no longer the importer's
  }
}

// Each face names 1 or more vertices that exist, and the mesh's primitive types are those of its
// faces; otherwise the file is malformed (an importer trusted counts that the data did not hold).
void check_imported(const aiScene& scene, const std::string& name) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* am = scene.mMeshes[m];
    auto fail = [&](const std::string& problem) {
      throw std::runtime_error("mesh " + name + " is malformed: mesh " + std::to_string(m) + " " +
                               problem);
    };
    if (!am || (am->mNumVertices > 0 && !am->mVertices) || (am->mNumFaces > 0 && !am->mFaces))
      fail("lacks its vertex or face data");
    unsigned types = 0;
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices == 0 || !face.mIndices)
        fail("has a face (" + std::to_string(f) + ") with no vertices");
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= am->mNumVertices)
          fail("has a face (" + std::to_string(f) + ") naming vertex " +
               std::to_string(face.mIndices[k]) + " of " + std::to_string(am->mNumVertices));
      types |= face.mNumIndices == 1   ? aiPrimitiveType_POINT
               : face.mNumIndices == 2 ? aiPrimitiveType_LINE
               : face.mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                       : aiPrimitiveType_POLYGON;
    }
    constexpr unsigned kTypes = aiPrimitiveType_POINT | aiPrimitiveType_LINE |
                                aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON;
    if ((am->mPrimitiveTypes & kTypes) != types)
      fail("has faces that disagree with its primitive types");
  }
}

}  // namespace

Mesh load_mesh(const std::filesystem::path& path, const MeshLimits& limits) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw std::runtime_error("mesh file " + path.string() + " does not exist");
  // Not a FIFO or a device: reading one could block or never end.
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error("mesh file " + path.string() + " is not a regular file");
  auto size = std::filesystem::file_size(path, ec);
  if (ec) throw std::runtime_error("cannot read mesh file " + path.string() + ": " + ec.message());
  if (size > limits.max_bytes)
    throw std::runtime_error("mesh file " + path.string() + " is larger than " +
                             std::to_string(limits.max_bytes) + " bytes");
  std::ifstream in(path, std::ios::binary);
  std::string bytes(size, '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(size)))
    throw std::runtime_error("cannot read mesh file " + path.string());
  std::string ext = path.extension().string();
  return load_mesh_bytes(bytes, ext.empty() ? ext : ext.substr(1), path.string(), limits);
}

Mesh load_mesh_bytes(std::string_view bytes, std::string_view format, const std::string& name,
                     const MeshLimits& limits) {
  if (bytes.size() > limits.max_bytes)
    throw std::runtime_error("mesh " + name + " is larger than " +
                             std::to_string(limits.max_bytes) + " bytes");
  std::string ext(format);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == "off" || ext == "ply" || ext == "glb" || ext == "stl") {
    try {
      if (ext == "off")
        check_off_text(bytes);
      else if (ext == "ply")
        check_ply(bytes);
      else if (ext == "glb")
        check_glb(bytes);
      else
        check_stl(bytes);
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot import mesh " + name + ": " + e.what());
    }
  }
  Assimp::Importer importer;
  keep_importers_of(importer, ext);
  if (importer.GetImporterCount() == 0)
    throw std::runtime_error("cannot import mesh " + name + ": no importer reads ." + ext +
                             " files");
  // The importer's own name for the file: the only one its IO system serves.
  const std::string file = "mesh." + ext;
  importer.SetIOHandler(new OneFileIOSystem(file, bytes));  // the importer owns it
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_COLORS | aiComponent_TEXCOORDS);
  // Read, then check what the importer made before any post-processing step sees it: Debian's
  // assimp is built with its assertions on, and a step that meets a malformed scene (a face with
  // no indices, primitive types that disagree with the faces) aborts the process.
  const aiScene* raw = importer.ReadFile(file, aiProcess_ValidateDataStructure);
  if (!raw || (raw->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || raw->mNumMeshes == 0)
    throw std::runtime_error("cannot import mesh " + name + ": " +
                             (raw ? "it holds no triangle mesh" : importer.GetErrorString()));
  check_imported(*raw, name);
  const aiScene* scene = importer.ApplyPostProcessing(
      aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_RemoveComponent |
      aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || scene->mNumMeshes == 0)
    throw std::runtime_error("cannot import mesh " + name + ": " +
                             (scene ? "it holds no triangle mesh" : importer.GetErrorString()));
  Mesh mesh;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    if (am->mNumFaces > limits.max_triangles - mesh.triangle_count())
      throw std::runtime_error("mesh " + name + " has more than " +
                               std::to_string(limits.max_triangles) + " triangles");
    auto base = static_cast<uint32_t>(mesh.positions.size());
    for (unsigned i = 0; i < am->mNumVertices; ++i) {
      Vec3 p{am->mVertices[i].x, am->mVertices[i].y, am->mVertices[i].z};
      for (int a = 0; a < 3; ++a)
        if (!std::isfinite(p[a]) || std::abs(p[a]) > 1e6)
          throw std::runtime_error("mesh " + name + ": vertex " + std::to_string(i) +
                                   " has a coordinate that is not finite or beyond 1e6");
      mesh.positions.push_back(p);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= am->mNumVertices)
          throw std::runtime_error("mesh " + name + ": face " + std::to_string(f) +
                                   " names vertex " + std::to_string(face.mIndices[k]) + " of " +
                                   std::to_string(am->mNumVertices));
        mesh.indices.push_back(base + face.mIndices[k]);
      }
    }
  }
  if (mesh.indices.empty())
    throw std::runtime_error("cannot import mesh " + name + ": it holds no triangles");
  mesh.compute_normals();
  return mesh;
}

}  // namespace scatter
