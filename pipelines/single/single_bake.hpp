// The `single` pipeline's bake (papers/single-scattering-inhomogeneous.md, section 4): from the
// voxelized medium to a set of Gaussian samples, each with its scattering coefficient and the
// spherical-harmonic projection of its direction-dependent optical depth (or transmittance).
//
// Stages (timed separately):
//   ddod       optical depth for n directions by slice sweeps (kernels/single/bake.cl), folded at
//              once into the first moment T(x) = sum_w exp(-tau(x, w)) w dOmega (equation 4)
//   divergence rho(x) = |div T(x)| by central differences
//   sampling   weighted Poisson-disk sampling by sample elimination, exactly `samples` points; the
//              local radius maps rho linearly onto [r/2, 2r] (the paper's rule; robust range:
//              5th-95th percentile of rho), raised to the power `adapt` (0.5 by default: a range
//              of [r/1.41, 1.41 r], measured better once the transmittance no longer comes from
//              the SH; 1: the paper's), a constant rho giving uniform spacing; with
//              density_guide, rho also grows with |grad sigma_t| inside the medium. Samples fill
//              the medium and a thin shell outside it, so that the Gaussians sum to one right up
//              to the surface (the render clips at the mesh)
//   gaussians  standard deviation `radius` x the local spacing, cut off at 3 sigma; weights
//              rescaled (4 passes) so the Gaussians sum to one at the voxel centres inside, then
//              `weight_fit` (20) least-squares iterations (CGLS) towards the same; a sample whose
//              Gaussian crosses a jump in the extinction (ratio above `split`, 2; 0 never) becomes
//              two pieces clipped by the interface plane (single_split.cpp); each sample's
//              (piece's) sigma_s is the Gaussian-weighted mean of its own medium on its side,
//              then `sigma_fit` (8) passes fit the splatted field to the voxels
//   sh         exact optical depth per channel from every sample along every direction (DDA),
//              projected onto `sh_order`^2 real spherical harmonics: of exp(-tau) (the paper, the
//              default) or of tau itself, clamped to 20, exponentiated when rendering (`sh_depth`
//              1). The second loses: the ringing of a band-limited tau near a face, clamped at
//              zero, darkens the directions that matter most (docs/BENCHMARKS.md)
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/pipeline.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

// Empty voxels the bake's grid needs around the solid (voxelize(..., {.margin = ...})): room for
// the shell of samples outside the surface.
constexpr int kSingleGridMargin = 4;

// A Gaussian's sigma is at least this many voxels: the weights make the Gaussians sum to one at
// the voxel centres only, and Gaussians much narrower than a voxel (many samples on a coarse
// grid) ripple between them (a box of 8^3 voxels at 12,000 samples was 21.8 % from the
// reference, 1.6 % with the floor; docs/pipelines/single.md).
constexpr double kMinSigmaVoxels = 0.5;

struct SingleBakeParams {
  int directions = 128;
  int samples = 25000;
  int sh_order = 5;            // bands, 2..8: 4..64 coefficients per channel (the paper: up to 5)
  bool sh_depth = false;       // project the optical depth (true) or the transmittance (false)
  double radius = 0.5;         // Gaussian sigma / local spacing
  int candidates = 5;          // candidates per sample for the elimination
  bool density_guide = false;  // sample density also follows |grad sigma_t| inside the medium
  int weight_fit = 20;  // least-squares (CGLS) iterations refining the weights after the passes
  double split = 2;     // extinction ratio above which a Gaussian is split at the jump (0: never)
  int sigma_fit =
      8;  // passes fitting each sample's sigma_s so the splatted field matches the voxels
  double adapt = 0.5;  // relative radius (2 - 1.5 t)^adapt from rho's rank t: 1 the paper's [r/2,
                       // 2r], 0 uniform
  uint32_t seed = 1;
  // The rules across settings (split's lower bound, samples x candidates); the settings table
  // (pipelines/single/single_info.cpp) checks each one's range.
  void check() const;
};

// The coarse set of n samples (setting `coarse`): the first quarter, two halvings of their
// progressive order (pipelines/single/sampling.hpp); none below 1024 samples.
inline int coarse_count(int n) {
  return n / 2 / 2 >= 256 ? n / 2 / 2 : 0;
}

struct SingleBake {
  SingleBakeParams params;
  int count = 0;
  std::vector<float> position;  // 3 per sample, scene units
  std::vector<float> depth_at;  // 3 per sample: where its optical depth is measured (its anchor
                                // inside the medium for shell samples, else its position)
  std::vector<float> sigma;     // Gaussian standard deviation per sample
  std::vector<float> weight;    // Gaussian amplitude per sample
  std::vector<float> sigma_s;   // 3 per sample
  std::vector<float>
      plane;      // 4 per sample: it counts where n . x <= d (xyz n, w d); zeros: everywhere
  int split = 0;  // samples split in two at a jump (count includes the extra pieces)
  // Per piece: its weight in the coarse set (the first coarse_count(samples) samples, widened by
  // cbrt(samples / coarse), and the pieces split off them); zero for the others. Empty: none.
  std::vector<float> coarse_weight;
  std::vector<float> sh;  // per sample, per channel, sh_order^2 coefficients
  // Sum of the Gaussians at the voxel centres inside: mean and relative standard deviation.
  double coverage_mean = 0, coverage_spread = 0;
  std::vector<StageTime> timings;

  size_t coefficients() const { return size_t(params.sh_order) * params.sh_order; }
  std::string serialize() const;
  // Throws std::runtime_error if `bytes` is not a complete bake of this format.
  static SingleBake deserialize(const std::string& bytes);
};

SingleBake bake_single(gpu::ClContext& cl, const VoxelGrid& grid, const SingleBakeParams& params,
                       const BakeProgress& progress = {});

// The pieces, for tests. First moment T per voxel (3 floats) for the given directions.
// `progress` (optional) hears the fraction of direction groups done.
std::vector<float> first_moment(gpu::ClContext& cl, const VoxelGrid& grid,
                                const std::vector<Vec3>& dirs,
                                const std::function<void(double)>& progress = {});
// |div T| per voxel, zero where the voxel holds no medium.
std::vector<float> divergence(const VoxelGrid& grid, const std::vector<float>& moment);
// Optical depth per (sample, direction, channel) from the sample to the grid's boundary.
std::vector<float> sample_depths(gpu::ClContext& cl, const VoxelGrid& grid,
                                 const std::vector<float>& positions,
                                 const std::vector<Vec3>& dirs);
// Sum of the baked Gaussians at p.
double gaussian_sum(const SingleBake& bake, const Vec3& p);

}  // namespace scatter
