// Density fields d(x) >= 0 that scale the medium's coefficients, and opaque blockers inside it.
//
//   constant  {"type": "constant", "value": 1}
//   layers    {"type": "layers", "axis": [0,1,0], "thickness": 0.25, "values": [0.2, 1.0]}
//   noise     {"type": "noise", "scale": 3, "octaves": 5, "min": 0.2, "max": 1.0, "marble": false,
//              "seed": 1}
//   grid      {"type": "grid", "file": "smoke.json"}   (header: dims, data, bounds; float32 raw)
//   blocker   {"type": "blocker", "shape": {...}, "sigma_a": 1000, "inner": <density>}
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "protocol/json_reader.hpp"
#include "scene/shapes.hpp"

namespace scatter {

class DensityField {
 public:
  virtual ~DensityField() = default;
  virtual double density(const Vec3& p) const = 0;
  // True inside an opaque blocker; there the medium is replaced by a pure absorber.
  virtual bool blocked(const Vec3&) const { return false; }
  virtual double blocker_sigma_a() const { return 0; }
  // True when density() is the same everywhere and nothing is blocked.
  virtual bool homogeneous() const { return false; }
  // What the field is, as a content address: the SHA-256 of its canonical JSON (and of a grid's
  // data), set by parse_density; empty for a field made in code.
  const std::string& id() const { return id_; }
  void set_id(std::string id) { id_ = std::move(id); }

 private:
  std::string id_;
};

struct GridLimits {
  int max_dim = 512;
};

// Reads a density object; grid files are resolved against `base_dir` and loaded now, so that a bad
// file is reported while the scene is parsed.
std::shared_ptr<const DensityField> parse_density(JsonObject& obj,
                                                  const std::filesystem::path& base_dir,
                                                  const GridLimits& limits = {});

// Fractal gradient noise in [-1, 1] (roughly), deterministic for a seed.
double fractal_noise(const Vec3& p, int octaves, unsigned seed);

}  // namespace scatter
