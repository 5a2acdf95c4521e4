// The plane-parallel slab solved by the lbl pipeline's lattice, for comparison with the
// reference's transport solution (pipelines/reference/slab.hpp, same parameters): a column of
// lattice nodes across the slab, periodic sideways, open at both faces. The collimated beam's
// scattered power per layer (Beer-Lambert along mu0, as the light march computes it) is the
// lattice's source, or with `second` (the default) the second scattering that power gives,
// computed exactly per layer, and with `gathers` (default 3, the pipeline's) the next orders
// from it on coarser layers, the lattice from the last. R and T are read as the pipeline's view
// pass reads the medium with tms 0 (its default TMS reading is a radiance correction away from the
// forward peak, which a flux integrates): the single scattering exactly (quadrature over
// directions, HG phase), the gathered orders and the lattice's scattered power per layer (the later
// events; without `second`, the second and later) emitted isotropically with the transport's escape
// probability through each face, and with g != 0 the forward-scattered light's scattering by the HG
// phase. `scaled_view`: the whole slab as the delta-Eddington scaled problem instead. `orders`: the
// real medium's low orders exactly, the lattice only for the rest (a diagnostic of the lattice's
// tail). R_lattice and T_lattice: what the lattice itself lets out through its open faces at
// steady state (its 6 directions, the orders it carries), for comparison.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/lbl/lbl_limits.hpp"
#include "pipelines/reference/slab.hpp"

namespace scatter::lbl {

struct LblSlabOptions {
  double layer_tau = 0.1;  // optical thickness of a layer (at most; at least 32 layers)
  double tolerance = 1e-6;
  int max_steps = 400000;
  bool escape = true;        // scale each layer's emission by the escape correction (escape.hpp)
  bool scaled_view = false;  // 1: read the whole slab as the delta-Eddington scaled problem
  bool second = true;        // as the pipeline's setting: the second scattering exactly
  // With `second`, as the pipeline's setting (and its default): the orders 2 to gathers + 1
  // gathered exactly (the third and later on layers as coarse as the pipeline's grid, second.hpp),
  // the lattice from the last of them.
  int gathers = 3;
  // N in [2, 32]: the real medium's orders 2 to N exactly, the lattice from order N's light (a
  // diagnostic: what the lattice's tail costs; not a pipeline setting; `second` and
  // `scaled_view` do not apply; tau at most 100). 0: off.
  int orders = 0;
};

struct SingleScattering {
  double R = 0, T = 0;
};

// Fractions of the incident power.
struct LblSlabResult {
  double R = 0, T = 0;
  double R_diffuse = 0, R_specular = 0, T_diffuse = 0, T_direct = 0;
  double R_single = 0, T_single = 0;     // leaving after exactly one scattering (exact)
  double R_forward = 0, T_forward = 0;   // the forward-scattered light's scattering (g != 0)
  double R_lattice = 0, T_lattice = 0;   // the lattice's own boundary flux (the orders it carries)
  std::vector<SingleScattering> orders;  // with `orders`: what leaves after 2, 3, ... scatterings
  double absorbed = 0;                   // 1 - R - T at steady state
  int layers = 0, steps = 0;
  bool converged = false;
};

void to_json(nlohmann::json& j, const LblSlabResult& r);

// The slab's single scattering (fractions of the incident power leaving through the lit and the
// other face after exactly one scattering), HG phase, by quadrature: no lattice involved.
SingleScattering slab_single_scattering(const SlabParams& params);

// Throws ValidationError for parameters out of range or that the lattice does not model (an
// infinite slab, ior != 1).
LblSlabResult run_lbl_slab(gpu::ClContext& cl, const SlabParams& params,
                           const LblSlabOptions& options = {});

}  // namespace scatter::lbl
