// JSON messages: nlohmann's own fuzzer check (parse -> dump -> parse -> dump is stable), that what
// the project's parse_json accepts nlohmann's non-throwing parse accepts as the same value, and the
// message readers that are pure functions today (a lights array, as a WebSocket "lights" message
// carries).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>

#include "fuzz_util.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json j1 = nlohmann::json::parse(text, nullptr, false);
  // The project's parse_json rejects what nlohmann rejects, and documents nested deeper than its
  // bound; it accepts the rest.
  nlohmann::json ours;
  bool accepted = scatter::fuzz::parse(text, ours);
  if (accepted && (j1.is_discarded() || ours != j1)) std::abort();
  if (j1.is_discarded()) return 0;
  std::string s1 = j1.dump();
  nlohmann::json j2 = nlohmann::json::parse(s1, nullptr, false);
  if (j2.is_discarded() || j2.dump() != s1) std::abort();
  if (j1.is_object() && j1.contains("lights")) {
    try {
      scatter::parse_lights(j1["lights"], "lights");
    } catch (const std::runtime_error&) {
    }
  }
  return 0;
}
