// Marching and diffusion interleaved, as in the paper's Table I: rays advance `k` steps per
// round, the deposit so far becomes the lattice's source, and the lattice runs a few steps before
// the next round; once every ray has stopped, the lattice converges as usual. The steady state is
// the sequential one's; what changes is when the diffusion starts.
#pragma once

#include "pipelines/lbl/lattice.hpp"
#include "pipelines/lbl/light_rays.hpp"

namespace scatter::lbl {

struct InterleaveResult {
  int rounds = 0;
  int lattice_steps = 0;  // taken between rounds (not counting the final convergence)
};

// Marches the rays in rounds of `k` fixed steps of `step` scene units (straight rays too), each
// followed by `lattice_steps` steps of `lattice` with the current source; deposits as march().
InterleaveResult march_interleaved(gpu::ClContext& cl, const ClVolume& v, const cl::Buffer& rays,
                                   int count, bool bend, double step, double cutoff, double g,
                                   cl::Buffer& deposit, cl::Buffer& source, Lattice& lattice, int k,
                                   int lattice_steps, cl::Buffer* flow = nullptr);

}  // namespace scatter::lbl
