#include "pipelines/lbl/slab.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "pipelines/lbl/lattice.hpp"

namespace scatter::lbl {
namespace {

void check(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw ValidationError(field, problem);
}

}  // namespace

void to_json(nlohmann::json& j, const LblSlabResult& r) {
  j = {{"solver", "lbl"},
       {"R", r.R},
       {"T", r.T},
       {"R_diffuse", r.R_diffuse},
       {"R_specular", r.R_specular},
       {"T_diffuse", r.T_diffuse},
       {"T_direct", r.T_direct},
       {"absorbed", r.absorbed},
       {"layers", r.layers},
       {"steps", r.steps},
       {"converged", r.converged}};
}

LblSlabResult run_lbl_slab(gpu::ClContext& cl, const SlabParams& p, const LblSlabOptions& o) {
  check(std::isfinite(p.tau), "tau",
        "the lbl solver needs a finite slab (the lattice has a node per layer)");
  check(p.tau > 0 && p.tau <= 1000, "tau", "must be in (0, 1000] for the lbl solver");
  check(p.albedo >= 0 && p.albedo <= 1, "albedo", "must be in [0, 1]");
  check(p.g > -1 && p.g < 1, "g", "must be in (-1, 1)");
  check(p.mu0 > 0 && p.mu0 <= 1, "mu0", "must be in (0, 1]");
  check(p.ior == 1, "ior", "the lbl solver has no refracting boundary: only 1 is supported");

  LblSlabResult r;
  r.layers = std::clamp(static_cast<int>(std::ceil(p.tau / o.layer_tau)), 32, 20000);
  const double dtau = p.tau / r.layers;  // sigma_t dx of a layer (lattice units: dx = 1)
  // The lattice: one node per layer, the same coefficients for all channels.
  Volume v;
  v.nx = v.ny = 1;
  v.nz = r.layers;
  v.voxel = 1;
  v.sigma_s.assign(3 * v.count(), static_cast<float>(p.albedo * dtau));
  v.sigma_t.assign(3 * v.count(), static_cast<float>(dtau));
  LatticeOptions lo{.blocked = false, .edges = {Edge::Periodic, Edge::Periodic, Edge::Open}};
  Lattice lattice(cl, lattice_coefficients(v, p.g), lo);
  // The beam (power 1 per node's cross-section, travelling +z), delta-Eddington scaled like the
  // lattice: the forward fraction g of its scattering stays in the beam, so it attenuates with
  // sigma_t' = (1 - a g) sigma_t and scatters in layer k what enters it times
  // a' (1 - exp(-dtau' / mu0)), a' = a (1 - g) / (1 - a g).
  const double dtau_r = (1 - p.albedo * p.g) * dtau;
  const double albedo_r = dtau_r > 0 ? p.albedo * (1 - p.g) * dtau / dtau_r : 0;
  std::vector<float> source(3 * v.count());
  for (int k = 0; k < r.layers; ++k) {
    double in = std::exp(-k * dtau_r / p.mu0);
    double s = in * albedo_r * -std::expm1(-dtau_r / p.mu0);
    for (int c = 0; c < 3; ++c) source[3 * k + c] = static_cast<float>(s);
  }
  lattice.set_source(source);
  Convergence c = lattice.converge(o.tolerance, o.max_steps, 64);
  r.steps = c.steps;
  r.converged = c.converged;
  // Leaving per step: -z out of the first layer (reflected), +z out of the last (transmitted).
  std::vector<float> f = lattice.state();
  const size_t n = lattice.nodes();
  const int up = 4, down = 5;  // +z, -z
  r.R_diffuse = f[(down * 3) * n + 0];
  r.T_direct = std::exp(-p.tau / p.mu0);
  // What the scaled beam carries out beyond the unscattered part was scattered forward.
  r.T_diffuse = f[(up * 3) * n + (n - 1)] + std::exp(-r.layers * dtau_r / p.mu0) - r.T_direct;
  r.R = r.R_diffuse + r.R_specular;
  r.T = r.T_diffuse + r.T_direct;
  r.absorbed = 1 - r.R - r.T;
  return r;
}

}  // namespace scatter::lbl
