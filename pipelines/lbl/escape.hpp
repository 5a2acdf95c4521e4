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

#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl {

// P per voxel and channel (3 floats per voxel; 1 where nothing scatters), on the device.
std::vector<float> exact_escape(gpu::ClContext& cl, const Volume& v, double g, int directions = 32);

// P_lattice of the 6-direction lattice with collision chances `pt` (3 per node, open edges).
std::vector<float> lattice_escape(const LatticeCoefficients& c);

// m per node and channel from the two, at least 0 (1 where P_lattice is 1). Deep inside it may
// pass 1 a little: the lattice's axis-aligned escape, exp(-tau), beats isotropic emission's
// E2-weighted one there, and m > 1 gives that light back (m (1 - P_lattice) = 1 - P < 1: no
// node sends on more than it would keep).
std::vector<float> escape_factor(const std::vector<float>& exact,
                                 const std::vector<float>& lattice);

}  // namespace scatter::lbl
