// Scene JSON text -> parse_json -> parse_scene, files resolved against a folder of small assets.
// Any exception other than std::runtime_error (ValidationError is one) would reach a user as a 500
// or end the process: it is left to abort the run.
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "fuzz_util.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json json;
  if (!scatter::fuzz::parse(text, json)) return 0;
  try {
    scatter::Scene scene = scatter::parse_scene(json, scatter::fuzz::assets_dir());
    scatter::fuzz::check_mesh(*scene.mesh);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
