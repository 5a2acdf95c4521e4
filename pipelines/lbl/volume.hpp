// The lbl pipeline's material volume (the paper's Init pass): per voxel sigma_s and sigma_t
// (RGB, per scene unit), the refractive index n (1 outside, the medium's ior inside, blended by
// occupancy, smoothed with a Gaussian) and its gradient, on a grid padded to whole lattice
// blocks; and the lattice's per-node coefficients derived from it.
#pragma once

#include <vector>

#include "gpu/cl_context.hpp"
#include "scene/voxelizer.hpp"

namespace scatter::lbl {

struct Volume {
  int nx = 0, ny = 0, nz = 0;  // multiples of the block size
  Vec3 origin;
  double voxel = 0;
  std::vector<float> sigma_s, sigma_t;  // 3 per voxel
  std::vector<float> occupancy;         // 1 per voxel
  std::vector<float> n;                 // 1 per voxel, smoothed
  std::vector<float> grad;              // 3 per voxel, d n / d x per scene unit
  bool constant_n = true;               // n is 1 everywhere: rays go straight

  size_t count() const { return size_t(nx) * ny * nz; }
  size_t index(int i, int j, int k) const { return (size_t(k) * ny + j) * nx + i; }
};

// Copies the voxel grid into a volume whose sides are padded (with empty voxels, at the high
// end) to multiples of `block`, and sets n from `ior` and the occupancy.
Volume make_volume(const VoxelGrid& grid, double ior, double smooth_voxels, int block);

// Sets n (one value per voxel), smooths it with a Gaussian of `smooth_voxels` standard deviation
// (0: none; edges clamp) and takes the gradient by central differences (one-sided at the edges).
void set_index(Volume& v, std::vector<float> n, double smooth_voxels);

// Per node and channel: pt = 1 - exp(-sigma_t' dx), ps = pt sigma_s' / sigma_t' (the chances of
// any collision and of a scattering one in a lattice step) and w = sigma_s (1 - exp(-sigma_t'
// dx)) / sigma_t' (scattered power per unit of power crossing the node). Primed coefficients
// are the similarity-reduced ones (sigma_s' = (1 - g) sigma_s), which carry the anisotropy into
// the isotropic lattice.
// The same for the diagonal directions of the 18-direction lattice, which cross sqrt(2) dx.
struct LatticeCoefficients {
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> pt, ps, w;                 // 3 per node
  std::vector<float> pt_diag, ps_diag, w_diag;  // 3 per node (18-direction lattice)
  // 3 per node, or empty (all 1): the fraction of each node's emission (what it scatters and
  // its source) the lattice carries on (pipelines/lbl/escape.hpp).
  std::vector<float> emit;
};
LatticeCoefficients lattice_coefficients(const Volume& v, double g);

// The volume's arrays on the device.
struct ClVolume {
  cl::Buffer sigma_s, sigma_t, n, grad;
  cl_float3 origin{};
  float voxel = 0;
  int nx = 0, ny = 0, nz = 0;
};
ClVolume upload_volume(gpu::ClContext& cl, const Volume& v);

}  // namespace scatter::lbl
