// The `psf` pipeline's `orders` model (model 1, the default; docs/pipelines/psf.md): the multiply
// scattered light of one light, order by order, on a coarse level of its pyramid
// (kernels/psf/orders.cl). Each order's light spreads by a Gaussian and drifts along the light
// by the flight of a persistent random walk (psf_model.hpp: order_flight) with the medium's mean
// mean free path; light reaching no medium is lost. With `conserve` (the default) each source
// voxel's light is scaled so that its flight's collisions, weighted by the local extinction, take
// the share of the flight that stays inside the mesh: dense parts collide more, sparse parts let
// the light fly further, and no order gains power. The march reads the bands (orders 1, 2 and
// the rest) and gives each its phase, HG(g^(m+1)) about the light's direction.
#pragma once

#include <array>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/psf/light_pyramid.hpp"

namespace scatter::psf {

struct OrderParams {
  double g = 0;
  std::array<double, 3> mean_sigma_t{};  // c over the medium's voxels, per channel
  int level = -1;                        // the pyramid level the orders run on; -1: chosen
  double tolerance = 1e-3;               // stop once an order's power is below this of the first
  int max_orders = 256;
  int flights =
      3;  // Gaussians per flight: 1, or 3 (the exponential flight's shape; flight_mixture)
  double drift = 0.5;  // the share of the flights' drift applied (calibrated_drift)
  bool tail = true;    // sum the orders past a steady decay as a geometric series
  // Scale each order's source so that its flight's collisions take what stays inside the mesh
  // (kernels/psf/orders.cl: order_scale) instead of capping b at the albedo times c_mean.
  bool conserve = true;
};

// An exponential flight (mean 1, isotropic) as Gaussians: per-axis standard deviations and
// weights whose radial distribution follows 1 - e^-r within 0.053 (one Gaussian: 0.37), with the
// flight's E r^2 = 2 kept exactly (fitted on the CPU; tests/unit/pipelines/psf checks both).
struct FlightGaussian {
  double sigma, weight;
};
std::vector<FlightGaussian> flight_mixture(int flights);

struct Orders {
  cl::Buffer
      bands;  // 4 float4 per voxel of `level`: phi_1, phi_2, sum_{m>=3} phi_m, sum g^(m+1) phi_m
  int level = -1, nx = 0, ny = 0, nz = 0;
  float cell = 0;     // the level's voxel, world units
  int count = 0;      // orders computed
  double lambda = 0;  // the decay per order the tail was summed with (0: no tail)
  int flights = 0;    // the parameters it was built with
  double drift = 0;
  bool tail = false;
  bool conserve = false;
  int normalisations = 0;  // conserve: flights whose collisions were normalised (kernels changed)
  double ms = 0;
};

// The share of the walk's drift the orders apply, calibrated against the reference (BENCHMARKS.md:
// sphere at g 0.7 and 0.9, checked on the bunny at g 0.2): min(0.5, 2.5 (1 - g)). The camera sees
// the light that turned back, which the walk's mean displacement does not follow.
double calibrated_drift(double g);

// The level the orders run on: the coarsest (at most 3) whose voxel is at most a third of the
// first flight's spread in the densest channel, unless `params.level` names one.
int orders_level(const OrderParams& params, float voxel, int levels);

// `occupancy`: one float per voxel of `medium` (its share inside the mesh), read with `conserve`.
Orders build_orders(gpu::ClContext& cl, const ClMedium& medium, const cl::Buffer& occupancy,
                    const Pyramid& pyramid, const cl::Buffer& lights, int light,
                    const OrderParams& params);

}  // namespace scatter::psf
