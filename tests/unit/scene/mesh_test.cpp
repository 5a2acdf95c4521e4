#include "scene/mesh.hpp"

#include <gtest/gtest.h>

#include <cstring>

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
  for (auto& c : kCorners) s += "v " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  for (auto& t : kTriangles) s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
  return s;
}

std::string cube_ply() {
  std::string s = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (auto& c : kCorners) s += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  for (auto& t : kTriangles) s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  return s;
}

std::string cube_stl() {
  // STL repeats the corners per facet; the importer must weld them.
  std::string s = "solid cube\n";
  for (auto& t : kTriangles) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const double* c = kCorners[t[k]];
      s += "   vertex " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
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
      {"buffers", {{{"byteLength", bin.size()},
                    {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}},
                       {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}}}},
      {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
                      {"min", {0, 0, 0}}, {"max", {1, 1, 1}}},
                     {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}}};
  return g.dump();
}

std::string cube_file(const std::string& ext) {
  if (ext == "obj") return cube_obj();
  if (ext == "ply") return cube_ply();
  if (ext == "stl") return cube_stl();
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

INSTANTIATE_TEST_SUITE_P(Formats, MeshImport, ::testing::Values("obj", "ply", "stl", "gltf"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(Mesh, WatertightCheckFindsHolesAndFlippedFaces) {
  Mesh m;
  for (auto& c : kCorners) m.positions.push_back({c[0], c[1], c[2]});
  for (auto& t : kTriangles) m.indices.insert(m.indices.end(), {uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])});
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

}  // namespace
}  // namespace scatter
