#include "scene/mesh.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <future>
#include <thread>

#include "../test_util.hpp"

namespace scatter {
namespace {

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

// Runs `load` on a thread of its own and gives it `seconds`: a load that blocks (on a FIFO) or
// loops fails the test instead of hanging the test binary (the thread is left behind).
template <class Load>
std::optional<std::string> error_within(Load load, double seconds, bool* timed_out) {
  auto done = std::make_shared<std::promise<std::optional<std::string>>>();
  auto result = done->get_future();
  std::thread([done, load] {
    try {
      load();
      done->set_value(std::nullopt);
    } catch (const std::runtime_error& e) {
      done->set_value(std::string(e.what()));
    }
  }).detach();
  *timed_out = result.wait_for(std::chrono::duration<double>(seconds)) != std::future_status::ready;
  return *timed_out ? std::optional<std::string>("timed out") : result.get();
}

// The error load_mesh_bytes gives for `bytes` as `format`, within 10 s; FAILs without one.
std::string import_error(const std::string& bytes, const std::string& format) {
  bool timed_out = false;
  auto error =
      error_within([bytes, format] { load_mesh_bytes(bytes, format, "upload"); }, 10, &timed_out);
  EXPECT_FALSE(timed_out) << format << " import still running after 10 s";
  EXPECT_TRUE(error.has_value()) << format << " import accepted a malformed file";
  return error.value_or("");
}

#define EXPECT_CONTAINS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

// The three uploads of issue 17 that killed the daemon: counts larger than the data (assimp's OFF
// reader left faces with no indices and a post-processing assertion aborted).
TEST(MeshOff, CountsLargerThanTheDataAreRejected) {
  auto dir = test::scratch_dir("mesh_off_counts");
  for (const char* text : {"OFF\n3 1 0\n0 0 0\n", "OFF\n4 2 0\n", "OFF\n100 100 0\n"}) {
    auto path = test::write_file(dir / "lying.off", text);
    try {
      load_mesh(path);
      ADD_FAILURE() << "accepted " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_CONTAINS(std::string(e.what()), "lying.off");
      EXPECT_CONTAINS(std::string(e.what()), "vertices, the file holds");
    }
  }
  EXPECT_CONTAINS(import_error("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off"),
                  "counts 2 faces, the file holds 1");
}

TEST(MeshOff, MalformedFilesGetAClearError) {
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  // assimp clamps an index past the vertices to the last one; this is an error.
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n" + tri + "3 0 1 7\n", "off"),
                  "names vertex \"7\"; there are 3");
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n0 nan 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off"),
                  "\"nan\" is not a finite number");
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n1e999 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off"),
                  "is not a finite number");
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n" + tri + "10 0 1 2 0 1 2 0 1 2 0\n", "off"),
                  "3 to 9");  // assimp drops it
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n" + tri + "3 0 1\n", "off"), "names fewer than 3");
  EXPECT_CONTAINS(import_error("OFF\n3 1 0\n" + tri + "3 0 1 2\n0 0 0\n", "off"),
                  "holds more than");
  // Counts are tokens (as assimp reads them): a missing edge count takes the first coordinate.
  EXPECT_CONTAINS(import_error("OFF\n3 1\n" + tri + "3 0 1 2\n", "off"),
                  "vertex 0 needs 3 numbers");
  EXPECT_CONTAINS(import_error("OFF\n99999999999 1 0\n", "off"), "three counts");
  EXPECT_CONTAINS(import_error("3 1 0\n" + tri + "3 0 1 2\n", "off"), "must start with OFF");
  // A line of 4096 characters or more would overflow assimp's line buffer.
  EXPECT_CONTAINS(
      import_error("OFF\n3 1 0\n0 0 0" + std::string(5000, ' ') + "\n1 0 0\n0 1 0\n3 0 1 2\n",
                   "off"),
      "longer than 4000 characters");
  const char with_nul[] = "OFF\n3 1 0\n0 0 0\0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_CONTAINS(import_error(std::string(with_nul, sizeof with_nul - 1), "off"), "NUL");
}

TEST(MeshPly, MalformedFilesGetAClearError) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  // Found by fuzz_mesh: a face row that is not a number left a face with no indices and primitive
  // types that disagreed with the faces; assimp's triangulation asserted and aborted the process.
  EXPECT_CONTAINS(import_error(header + tri + "3 0 1 2\nz\n", "ply"),
                  "does not match the header's properties");
  // Found by fuzz_mesh: a header with no end_header made assimp's PLY reader loop without end.
  EXPECT_CONTAINS(
      import_error("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\n1 0 0\n", "ply"),
      "no end_header");
  EXPECT_CONTAINS(import_error(header + tri + "3 0 1 2\n", "ply"),
                  "element 1 has 1 rows, its header says 2");
  EXPECT_CONTAINS(import_error(header + tri + "3 0 1 2\n3 0 1 9\n", "ply"),
                  "is out of range");  // assimp's own validation
  EXPECT_CONTAINS(import_error(header + "0 inf 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n", "ply"),
                  "does not match");
  EXPECT_CONTAINS(
      import_error(
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nnonsense\nend_header\n",
          "ply"),
      "not a PLY header keyword");
  // Counts far beyond the data: refused before anything is allocated for them.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n" +
      std::string(36, '\0');
  EXPECT_CONTAINS(import_error(binary, "ply"), "data ends inside row 3");
  std::string list =
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int "
      "vertex_indices\n"
      "end_header\n\xff" +
      std::string(8, '\0');
  EXPECT_CONTAINS(import_error(list, "ply"), "data ends inside row 0 of element 0");
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

// A GLB whose lengths run past the file (fuzz.mesh: a JSON chunk of 0xfffffff9 bytes made
// assimp ask for 4 GiB) is refused before assimp reads it; the corpus's cube still loads.
TEST(MeshGlb, LengthsPastTheFileAreRejected) {
  std::ifstream in(test::source_path("tests/fuzz/corpus/mesh/cube.glb"), std::ios::binary);
  std::string cube((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GT(cube.size(), 21u);
  cube.erase(0, 1);  // the fuzz corpus's format byte
  EXPECT_EQ(load_mesh_bytes(cube, "glb", "upload").triangle_count(), 12u);
  auto with = [&](size_t at, uint32_t x) {
    std::string b = cube;
    for (int i = 0; i < 4; ++i) b[at + i] = char((x >> (8 * i)) & 0xff);
    return b;
  };
  EXPECT_CONTAINS(import_error(with(12, 0xfffffff9u), "glb"), "chunk 0 says 4294967289 bytes");
  EXPECT_CONTAINS(import_error(with(8, uint32_t(cube.size() + 1)), "glb"), "the file holds");
  EXPECT_CONTAINS(import_error(cube.substr(0, 10), "glb"), "12-byte header");
  EXPECT_CONTAINS(import_error(with(4, 7), "glb"), "version 7");
}

// A binary STL whose facet count, times 50 in 32 bits, wraps to the file's size: assimp would
// take it as binary and allocate 3 vertices a facet (3 GiB) before reading past the file.
TEST(MeshStl, ACountThatWrapsIsRejected) {
  std::string b(88, '\0');
  const uint32_t count = 85899346u;  // 84 + 50 x count = 2^32 + 88
  for (int i = 0; i < 4; ++i) b[80 + i] = char((count >> (8 * i)) & 0xff);
  EXPECT_CONTAINS(import_error(b, "stl"), "counts 85899346 facets, 4294967384 bytes");
  std::string one(84 + 50, '\0');  // one facet, a true size: still read
  one[80] = 1;
  for (int v = 0; v < 3; ++v) {  // a triangle (0,0,0) (1,0,0) (0,1,0)
    float p[3] = {v == 1 ? 1.f : 0.f, v == 2 ? 1.f : 0.f, 0.f};
    std::memcpy(&one[84 + 12 + 12 * v], p, sizeof p);
  }
  EXPECT_EQ(load_mesh_bytes(one, "stl", "upload").triangle_count(), 1u);
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
