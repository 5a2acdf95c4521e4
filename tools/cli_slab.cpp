// scatterd slab --tau T|inf --albedo A --g G --mu0 M --ior N --solver reference|lbl [--photons K]
//               [--seed S] [--second 0|1] [--scaled-view 0|1]
//               [--orders N] [--json]
// lbl: the lbl pipeline's lattice at steady state (finite tau, ior 1; photons and seed unused).
#include <cmath>
#include <iostream>

#include "core/errors.hpp"
#include "gpu/gpu.hpp"
#include "pipelines/lbl/slab.hpp"
#include "pipelines/reference/slab.hpp"
#include "tools/commands.hpp"

namespace scatter::tools {
namespace {

struct SlabOptions {
  std::string tau = "1";
  SlabParams params;
  std::string solver = "reference";
  std::string device;
  bool json = false;
  lbl::LblSlabOptions lbl;
};

int run_slab(SlabOptions o) {
  if (o.tau == "inf") {
    o.params.tau = INFINITY;
  } else {
    size_t used = 0;
    try {
      o.params.tau = std::stod(o.tau, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != o.tau.size())
      throw ValidationError("--tau", "expects a number or inf, got \"" + o.tau + "\"");
  }
  if (o.solver != "reference" && o.solver != "lbl")
    throw ValidationError("--solver",
                          "unknown solver \"" + o.solver + "\" (known: reference, lbl)");
  gpu::Gpu gpu(gpu::GpuOptions{o.device});
  nlohmann::json j;
  if (o.solver == "lbl")
    j = lbl::run_lbl_slab(gpu.cl(), o.params, o.lbl);
  else
    j = run_reference_slab(gpu.cl(), o.params);
  if (o.json) {
    std::cout << j.dump() << "\n";
  } else {
    for (const auto& [k, v] : j.items()) std::cout << k << " = " << v << "\n";
  }
  return 0;
}

}  // namespace

Handler add_slab_command(CLI::App& app) {
  auto o = std::make_shared<SlabOptions>();
  CLI::App* cmd = app.add_subcommand(
      "slab", "Reflectance and transmittance of a plane-parallel slab lit by a collimated beam");
  cmd->add_option("--tau", o->tau, "Optical thickness, or inf for a half-space")
      ->capture_default_str();
  cmd->add_option("--albedo", o->params.albedo, "Single-scattering albedo")->capture_default_str();
  cmd->add_option("--g", o->params.g, "Henyey-Greenstein asymmetry")->capture_default_str();
  cmd->add_option("--mu0", o->params.mu0, "Cosine of the incidence angle")->capture_default_str();
  cmd->add_option("--ior", o->params.ior, "Refractive index of the slab (outside: 1)")
      ->capture_default_str();
  cmd->add_option("--photons", o->params.photons, "Photons to trace")->capture_default_str();
  cmd->add_option("--seed", o->params.seed, "Random seed")->capture_default_str();
  cmd->add_option("--solver", o->solver, "reference (transport, Monte Carlo) or lbl (the lattice)")
      ->capture_default_str();
  cmd->add_option("--device", o->device, "OpenCL device: P:D or part of its name");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->add_option("--second", o->lbl.second,
                  "lbl: 1 computes the second scattering exactly and starts the lattice from it "
                  "(the pipeline's setting `second`)")
      ->capture_default_str();
  cmd->add_option("--scaled-view", o->lbl.scaled_view,
                  "lbl: 1 reads the whole slab as the delta-Eddington scaled problem; 0 as the "
                  "pipeline's view pass reads the medium by default")
      ->capture_default_str();
  cmd->add_option("--gathers", o->lbl.gathers,
                  "lbl, with --second 1: the orders 2 to N + 1 gathered exactly, the third and "
                  "later at half resolution (the pipeline's setting `gathers`)")
      ->capture_default_str();
  cmd->add_option("--orders", o->lbl.orders,
                  "lbl: N in [2, 32] computes the real medium's orders 2 to N exactly and starts "
                  "the lattice from order N's light (a diagnostic); 0: off")
      ->capture_default_str();
  return [o] { return run_slab(*o); };
}

}  // namespace scatter::tools
