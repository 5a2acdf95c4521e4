// Mesh uploads: the first byte picks the format (obj, off, ply, stl, glb), the rest is the file;
// load_mesh_bytes, then what POST /api/assets does next (the watertight check, the volume).
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* const kFormats[] = {"obj", "off", "ply", "stl", "glb"};
  const char* format = kFormats[data[0] % 5];
  std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    scatter::MeshLimits limits;
    limits.max_triangles = 100'000;  // keeps each run short; the limit's own check is exercised
    scatter::Mesh mesh = scatter::load_mesh_bytes(bytes, format, "upload", limits);
    scatter::fuzz::check_mesh(mesh);
    scatter::check_watertight(mesh);
    (void)mesh.volume();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
