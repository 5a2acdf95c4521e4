#include "scene/mesh.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <future>
#include <thread>

#include "../test_util.hpp"
#include "mesh_import_errors.hpp"

namespace scatter {
namespace {

using test_mesh::error_within;
using test_mesh::import_error;

// The unit cube [0, 1]^3: 8 corners, 12 outward triangles.
const double kCorners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kTriangles[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                               {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string cube_obj() {
  std::string s;
  for (auto& c : kCorners)
    s += "v " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) +
         "\n";
  for (auto& t : kTriangles)
    s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
         std::to_string(t[2] + 1) + "\n";
  return s;
}

std::string cube_ply() {
  std::string s =
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (auto& c : kCorners)
    s += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  for (auto& t : kTriangles)
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
         "\n";
  return s;
}

std::string cube_off() {
  std::string s = "OFF\n# the unit cube\n8 12 0\n";
  for (auto& c : kCorners)
    s += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  for (auto& t : kTriangles)
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
         "\n";
  return s;
}

std::string cube_stl() {
  // STL repeats the corners per facet; the importer must weld them.
  std::string s = "solid cube\n";
  for (auto& t : kTriangles) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const double* c = kCorners[t[k]];
      s += "   vertex " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
           std::to_string(c[2]) + "\n";
    }
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid cube\n";
}

std::string base64(const std::string& in) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    for (int k = 3; k >= 0; --k) out += table[(v >> (6 * k)) & 63];
  }
  if (size_t rest = in.size() - i) {
    uint32_t v = uint8_t(in[i]) << 16 | (rest == 2 ? uint8_t(in[i + 1]) << 8 : 0);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += rest == 2 ? table[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string cube_gltf() {
  std::string bin;
  for (auto& c : kCorners)
    for (double x : c) {
      float f = static_cast<float>(x);
      bin.append(reinterpret_cast<const char*>(&f), 4);
    }
  for (auto& t : kTriangles)
    for (int k : t) {
      uint16_t i = static_cast<uint16_t>(k);
      bin.append(reinterpret_cast<const char*>(&i), 2);
    }
  nlohmann::json g = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"buffers",
       {{{"byteLength", bin.size()},
         {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", 8},
         {"type", "VEC3"},
         {"min", {0, 0, 0}},
         {"max", {1, 1, 1}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}}};
  return g.dump();
}

std::string cube_file(const std::string& ext) {
  if (ext == "obj") return cube_obj();
  if (ext == "ply") return cube_ply();
  if (ext == "stl") return cube_stl();
  if (ext == "off") return cube_off();
  return cube_gltf();
}

class MeshImport : public ::testing::TestWithParam<std::string> {};

TEST_P(MeshImport, CubeImportsWatertightWithUnitVolume) {
  const std::string& ext = GetParam();
  auto dir = test::scratch_dir("mesh_import_" + ext);
  auto path = test::write_file(dir / ("cube." + ext), cube_file(ext));
  Mesh m = load_mesh(path);
  EXPECT_EQ(m.triangle_count(), 12u);
  EXPECT_EQ(m.normals.size(), m.positions.size());
  WatertightReport r = check_watertight(m);
  EXPECT_TRUE(r.watertight()) << r.summary();
  EXPECT_NEAR(std::abs(m.volume()), 1.0, 1e-6);
  Aabb b = m.bounds();
  EXPECT_NEAR(b.lo.x, 0, 1e-6);
  EXPECT_NEAR(b.hi.z, 1, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshImport, ::testing::Values("obj", "ply", "stl", "off", "gltf"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(Mesh, WatertightCheckFindsHolesAndFlippedFaces) {
  Mesh m;
  for (auto& c : kCorners) m.positions.push_back({c[0], c[1], c[2]});
  for (auto& t : kTriangles)
    m.indices.insert(m.indices.end(), {uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])});
  EXPECT_TRUE(check_watertight(m).watertight());
  EXPECT_NEAR(m.volume(), 1.0, 1e-12);

  Mesh flipped = m;
  std::swap(flipped.indices[1], flipped.indices[2]);  // one triangle wound the other way
  WatertightReport f = check_watertight(flipped);
  EXPECT_EQ(f.misoriented_edges, 3u);
  EXPECT_FALSE(f.watertight());

  Mesh open = m;
  open.indices.resize(open.indices.size() - 6);  // drop the last face (two triangles)
  EXPECT_EQ(check_watertight(open).boundary_edges, 4u);
}

TEST(Mesh, ImportErrorsNameTheFile) {
  auto dir = test::scratch_dir("mesh_errors");
  auto path = test::write_file(dir / "junk.obj", "this is not a mesh\n");
  try {
    load_mesh(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("junk.obj"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_mesh(dir / "absent.ply"), std::runtime_error);
}

TEST(Mesh, StanfordBunnyIsWatertight) {
  Mesh m = load_mesh("/usr/share/glmark2/models/bunny.obj");
  EXPECT_GT(m.triangle_count(), 60000u);
  EXPECT_TRUE(check_watertight(m).watertight()) << check_watertight(m).summary();
}

TEST(Mesh, FacesNamingMissingVerticesAreRejected) {
  std::string obj = cube_obj() + "f 1 2 99\n";
  import_error(obj, "obj");
  EXPECT_CONTAINS(import_error("v 1e999 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj"), "not finite");
}

// An mtllib is not followed: a FIFO named there would block the import (assimp's default IO system
// opens it and waits for a writer); with only the upload's bytes served, the cube loads at once.
TEST(Mesh, MtllibOutsideTheFileIsNotOpened) {
  auto dir = test::scratch_dir("mesh_mtllib");
  ASSERT_EQ(::mkfifo((dir / "blocks.mtl").c_str(), 0600), 0);
  for (std::string lib : {std::string("blocks.mtl"), (dir / "blocks.mtl").string(),
                          std::string("../../../../../../../../etc/passwd")}) {
    auto path =
        test::write_file(dir / "cube.obj", "mtllib " + lib + "\nusemtl steel\n" + cube_obj());
    bool timed_out = false;
    auto triangles = std::make_shared<size_t>(0);
    auto error = error_within([triangles, path] { *triangles = load_mesh(path).triangle_count(); },
                              10, &timed_out);
    ASSERT_FALSE(timed_out) << "the import of an OBJ with mtllib " << lib << " blocked";
    EXPECT_FALSE(error.has_value()) << *error;
    EXPECT_EQ(*triangles, 12u);
  }
  // Nor is a FIFO opened as the mesh itself.
  bool timed_out = false;
  auto error = error_within([dir] { load_mesh(dir / "blocks.mtl"); }, 10, &timed_out);
  ASSERT_FALSE(timed_out);
  ASSERT_TRUE(error.has_value());
  EXPECT_CONTAINS(*error, "is not a regular file");
}

// The fuzz corpus's meshes are valid files of each upload format (the first byte picks the format).
TEST(Mesh, FuzzCorpusCubesLoadInEveryFormat) {
  const char* formats[] = {"obj", "off", "ply", "stl", "glb"};
  int loaded = 0;
  for (const auto& e :
       std::filesystem::directory_iterator(test::source_path("tests/fuzz/corpus/mesh"))) {
    std::string name = e.path().filename().string();
    if (name.rfind("cube", 0) != 0 && name.rfind("quads", 0) != 0) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    ASSERT_FALSE(bytes.empty());
    Mesh m =
        load_mesh_bytes(std::string_view(bytes).substr(1), formats[uint8_t(bytes[0]) % 5], name);
    EXPECT_EQ(m.triangle_count(), 12u) << name;
    EXPECT_TRUE(check_watertight(m).watertight()) << name;
    EXPECT_NEAR(std::abs(m.volume()), 1.0, 1e-6) << name;
    ++loaded;
  }
  EXPECT_EQ(loaded, 9);
}

TEST(Mesh, UnknownFormatsAndOversizedFilesAreRefused) {
  EXPECT_CONTAINS(import_error(cube_obj(), "nosuchformat"),
                  "no importer reads .nosuchformat files");
  MeshLimits small;
  small.max_bytes = 100;
  EXPECT_THROW(load_mesh_bytes(cube_obj(), "obj", "upload", small), std::runtime_error);
  small = {};
  small.max_triangles = 11;
  EXPECT_THROW(load_mesh_bytes(cube_obj(), "obj", "upload", small), std::runtime_error);
}

}  // namespace
}  // namespace scatter
