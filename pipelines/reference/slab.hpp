// The plane-parallel slab problem solved by the reference transport code: fractions of the
// incident power reflected and transmitted, for checking against transport theory and tables.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>

#include "gpu/cl_context.hpp"

namespace scatter {

struct SlabParams {
  double tau = 1;  // optical thickness; infinity for a half-space
  double albedo = 0.9;
  double g = 0;
  double mu0 = 1;  // cosine of the beam's incidence angle
  double ior = 1;  // the slab's refractive index; outside is 1
  long long photons = 1'000'000;
  uint32_t seed = 1;
};

// Fractions of the incident power. R includes the specular reflection, T the unscattered beam.
struct SlabResult {
  double R = 0, T = 0;
  double R_diffuse = 0, R_specular = 0, T_diffuse = 0, T_direct = 0;
  double R_single = 0, T_single = 0;  // escaping after exactly one scattering
  double R_stderr = 0, T_stderr = 0;
  double lost = 0;  // weight of photons still inside after the step bound (10^5 events)
  long long photons = 0;
};

void to_json(nlohmann::json& j, const SlabResult& r);

// Throws ValidationError for parameters out of range.
SlabResult run_reference_slab(gpu::ClContext& cl, const SlabParams& params);

}  // namespace scatter
