// Grid uploads: a grid header (JSON text: dims, bounds, format, data) and its raw float32 values,
// written as the upload writes them and read back through parse_density. A grid that loads must
// give a finite, non-negative density everywhere.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>

#include "fuzz_util.hpp"
#include "scene/density.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  std::string header = in.ConsumeRandomLengthString(2048);
  std::string raw = in.ConsumeRemainingBytesAsString();
  const auto& dir = scatter::fuzz::assets_dir();
  scatter::fuzz::write(dir / "upload.grid.json", header);
  scatter::fuzz::write(dir / "upload.raw", raw);
  nlohmann::json density = {{"type", "grid"}, {"file", "upload.grid.json"}};
  try {
    scatter::JsonObject o(density, "grid");
    auto field = scatter::parse_density(o, dir);
    for (double x : {-1.5, -0.99, -0.3, 0.0, 0.41, 0.999, 2.0})
      for (double y : {-0.7, 0.0, 0.5})
        for (double z : {-1.0, 0.25, 1.0}) {
          double d = field->density({x, y, z});
          if (!std::isfinite(d) || d < 0) std::abort();
        }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
