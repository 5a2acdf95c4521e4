// The lattice's escape correction (a Marshak-type boundary): next to a surface the 6-direction
// lattice lets too little light leave. Isotropic emission at a node leaves it through the open
// side in 1 of its 6 directions (the others run along the surface or into the medium), where
// transport lets about half leave: the collision density near the surface, which the view pass
// reads as the multiple term's emission, comes out too high (a slab at normal incidence: 1.5x
// in the reflected multiple term). Each node's emission (what it scatters and the source) is
// scaled by m = (1 - P) / (1 - P_lattice), where P is the chance that isotropic emission at the
// node leaves the medium without another interaction (exact, over 32 directions, through the
// delta-Eddington scaled sigma_t') and P_lattice the lattice's own (1/6 of the product of
// (1 - pt) along each axis to the grid's edge): the light carried on is what would interact
// again, so the lattice's collision density drops near surfaces to about the transport's. The
// light taken out is not lost from the image: the view pass gathers every collision with the
// exact view transmittance.
#pragma once

#include <array>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl {

// `count` directions on a Fibonacci spiral (3 floats each).
std::vector<float> fibonacci_directions(int count);

// How exact_escape with a stride > 1 covers the grid: the samples it computes (indices into
// the grid of every stride-th voxel, n[0] x n[1] x n[2]) and per voxel 0 (does not scatter: P 1),
// 1 (the trilinear mean of the samples around it: each scatters, in a medium, by sigma_t',
// within 25 % of the voxel's) or 2 (computed at the voxel itself: next to a surface, a blocker
// or a density step). `scaled`: sigma_t' per voxel and channel.
struct EscapeSampling {
  std::array<int, 3> n{};
  std::vector<cl_int> samples;
  std::vector<cl_char> mode;
};
EscapeSampling escape_sampling(const Volume& v, const std::vector<float>& scaled, int stride);

// P per voxel and channel (3 floats per voxel; 1 where nothing scatters), on the device. With
// `stride` s > 1, P is computed only at every s-th voxel along each axis (the samples some
// voxel needs); a scattering voxel inside one medium takes the trilinear mean of the samples
// around it (P is smooth over a mean free path, 10-16 voxels on the shipped scenes), one next
// to a surface, a blocker or a density step is computed itself (escape_sampling).
// With `far` > 0 (stride > 1 only) a ray crosses the voxels for its first `far` voxel widths
// and then a grid of half the resolution (coarse_sigma): about half the steps.
std::vector<float> exact_escape(gpu::ClContext& cl, const Volume& v, double g, int directions = 32,
                                int stride = 1, double far = 0);

// sigma_t' on the grid of 2x2x2 voxels per cell ((n + 1) / 2 per side), the mean of the 8
// (voxels past the grid's high end counted as empty); `scaled` 3 floats per voxel.
std::vector<float> coarse_sigma(const Volume& v, const std::vector<float>& scaled);

// P_lattice of the 6-direction lattice with collision chances `pt` (3 per node, open edges).
std::vector<float> lattice_escape(const LatticeCoefficients& c);

// m per node and channel from the two, at least 0 (1 where P_lattice is 1). Deep inside it may
// pass 1 a little: the lattice's axis-aligned escape, exp(-tau), beats isotropic emission's
// E2-weighted one there, and m > 1 gives that light back (m (1 - P_lattice) = 1 - P < 1: no
// node sends on more than it would keep).
std::vector<float> escape_factor(const std::vector<float>& exact,
                                 const std::vector<float>& lattice);

}  // namespace scatter::lbl
