// The checks of mesh files before assimp reads them (scene/mesh_checks.hpp): uploads whose
// counts or lengths lie about the data get a clear error instead of a crash, a hang or gigabytes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../test_util.hpp"
#include "mesh_import_errors.hpp"
#include "scene/mesh.hpp"

namespace scatter {
namespace {

using test_mesh::import_error;

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

// A GLB's JSON against its buffers (a review found these with libassimp alone: a version 1 file
// whose accessor overran its view aborted on an assertion, a sparse accessor without indices
// dereferenced null, one without a buffer view allocated count x its size, gigabytes for 544
// bytes): each refused naming what is wrong, before assimp reads it.
TEST(MeshGlb, WhatTheJsonSaysIsCheckedAgainstTheBuffers) {
  std::ifstream in(test::source_path("tests/fuzz/corpus/mesh/cube.glb"), std::ios::binary);
  std::string cube((std::istreambuf_iterator<char>(in)), {});
  cube.erase(0, 1);  // the fuzz corpus's format byte
  auto u32 = [](std::string& b, size_t at, uint32_t x) {
    for (int i = 0; i < 4; ++i) b[at + i] = char((x >> (8 * i)) & 0xff);
  };
  auto le32 = [&](size_t at) {
    uint32_t x = 0;
    for (int i = 3; i >= 0; --i) x = (x << 8) | static_cast<unsigned char>(cube[at + i]);
    return x;
  };
  const uint32_t json_bytes = le32(12);
  const nlohmann::json doc = nlohmann::json::parse(cube.substr(20, json_bytes));
  const std::string bin = cube.substr(20 + json_bytes);  // its chunk header and data
  auto glb = [&](const std::string& json, uint32_t version = 2) {
    std::string text = json;
    while (text.size() % 4) text += ' ';
    std::string b(20, '\0');
    b.replace(0, 4, "glTF");
    u32(b, 4, version);
    u32(b, 12, uint32_t(text.size()));
    u32(b, 16, 0x4E4F534A);
    b += text + bin;
    u32(b, 8, uint32_t(b.size()));
    return b;
  };
  auto edited = [&](auto change) {
    nlohmann::json d = doc;
    change(d);
    return glb(d.dump());
  };
  EXPECT_EQ(load_mesh_bytes(glb(doc.dump()), "glb", "upload").triangle_count(), 12u);
  EXPECT_CONTAINS(import_error(glb(doc.dump(), 1), "glb"), "version 1 (only glTF 2.0");
  EXPECT_CONTAINS(import_error(edited([](auto& d) {
                                 d["accessors"][0]["sparse"] = {{"count", 1}};
                               }),
                               "glb"),
                  "accessor 0 is sparse");
  EXPECT_CONTAINS(
      import_error(edited([](auto& d) { d["accessors"][1].erase("bufferView"); }), "glb"),
      "accessor 1 has no bufferView");
  EXPECT_CONTAINS(
      import_error(edited([](auto& d) { d["accessors"][0]["count"] = 100000000; }), "glb"),
      "accessor 0's count is 100000000, more than");
  EXPECT_CONTAINS(import_error(edited([](auto& d) { d["accessors"][0]["count"] = 9; }), "glb"),
                  "accessor 0 (9 elements of 12 bytes, 12 apart, from 0) runs past bufferView "
                  "0's 96 bytes");
  EXPECT_CONTAINS(
      import_error(edited([](auto& d) { d["bufferViews"][1]["byteLength"] = 73; }), "glb"),
      "bufferView 1 (96 + 73 bytes) runs past buffer 0's 168");
  EXPECT_CONTAINS(import_error(edited([](auto& d) { d["buffers"][0]["byteLength"] = 400; }), "glb"),
                  "buffer 0 says 400 bytes, its data holds 168");
  EXPECT_CONTAINS(import_error(edited([](auto& d) {
                                 d["bufferViews"][0]["byteOffset"] = 18446744073709551000ull;
                               }),
                               "glb"),
                  "bufferView 0's byteOffset is 18446744073709551000, more than");
  EXPECT_CONTAINS(
      import_error(edited([](auto& d) { d["meshes"][0]["primitives"][0]["indices"] = 5; }), "glb"),
      "names indices of no accessor");
  EXPECT_CONTAINS(import_error(edited([](auto& d) {
                                 d["extras"] = nlohmann::json::parse(std::string(100, '[') +
                                                                     std::string(100, ']'));
                               }),
                               "glb"),
                  "nests more than 64 deep");
  std::string odd = glb(doc.dump());
  u32(odd, 12, le32(12) - 1);  // the JSON's length no longer a multiple of 4
  EXPECT_CONTAINS(import_error(odd, "glb"), "not a multiple of 4");
}

// The review's reproductions, kept in the fuzz corpus (glb-*: a version 1 file whose accessor
// overran its view, sparse accessors without indices, without a buffer view, and overreading;
// stl-count-wraps): each refused by the checks, before assimp.
TEST(MeshGlb, TheCorpusReproductionsAreRefused) {
  int refused = 0;
  for (const auto& e :
       std::filesystem::directory_iterator(test::source_path("tests/fuzz/corpus/mesh"))) {
    const std::string name = e.path().filename().string();
    const bool glb = name.rfind("glb-", 0) == 0, stl = name.rfind("stl-", 0) == 0;
    if (!glb && !stl) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    ASSERT_GT(bytes.size(), 1u);
    EXPECT_CONTAINS(import_error(bytes.substr(1), glb ? "glb" : "stl"), glb ? "GLB: " : "STL: ")
        << name;
    ++refused;
  }
  EXPECT_EQ(refused, 5);
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

}  // namespace
}  // namespace scatter
