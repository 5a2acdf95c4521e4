// The plane-parallel slab solved by the lbl pipeline's lattice, for comparison with the
// reference's transport solution (pipelines/reference/slab.hpp, same parameters): a column of
// lattice nodes across the slab, periodic sideways, open at both faces. The collimated beam's
// scattered power per layer (Beer-Lambert along mu0, as the light march computes it) is the
// lattice's source; at steady state, what leaves through the lit face is R and through the other
// face the diffuse part of T.
#pragma once

#include <nlohmann/json.hpp>

#include "gpu/cl_context.hpp"
#include "pipelines/reference/slab.hpp"

namespace scatter::lbl {

struct LblSlabOptions {
  double layer_tau = 0.1;  // optical thickness of a layer (at most; at least 32 layers)
  double tolerance = 1e-6;
  int max_steps = 400000;
};

// Fractions of the incident power.
struct LblSlabResult {
  double R = 0, T = 0;
  double R_diffuse = 0, R_specular = 0, T_diffuse = 0, T_direct = 0;
  double absorbed = 0;  // 1 - R - T at steady state
  int layers = 0, steps = 0;
  bool converged = false;
};

void to_json(nlohmann::json& j, const LblSlabResult& r);

// Throws ValidationError for parameters out of range or that the lattice does not model (an
// infinite slab, ior != 1).
LblSlabResult run_lbl_slab(gpu::ClContext& cl, const SlabParams& params,
                           const LblSlabOptions& options = {});

}  // namespace scatter::lbl
