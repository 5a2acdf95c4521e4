// The lattice-Boltzmann diffusion of the lbl pipeline (kernels/lbl/lattice.cl): 6 axis directions
// and a rest state holding the light rays' deposit, stepped either over the whole grid at once
// (the global form) or in blocks of b^3 nodes that talk through interface buffers (the paper's
// form), until the irradiance at a few probes and the total energy stop changing.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl {

enum class Edge { Open = 0, Reflect = 1, Periodic = 2 };

struct LatticeOptions {
  bool blocked = true;  // the paper's blocks; false: one work item per node over the whole grid
  int block = 4;        // b (blocked): the grid's sides must be multiples of it
  int inner = 1;        // steps per launch inside a block (blocked); 1 matches the global form
  int directions = 6;   // 6 (the paper's) or 18 (Geist et al.'s, global form only)
  std::array<Edge, 3> edges{Edge::Open, Edge::Open, Edge::Open};  // periodic: global form only
};

struct Convergence {
  int steps = 0;  // lattice steps taken by this call
  bool converged = false;
  double change = 0;  // the last relative change measured
};

class Lattice {
 public:
  // Throws std::invalid_argument for sides that are not whole blocks, a periodic blocked edge or
  // a blocked 18-direction lattice.
  Lattice(gpu::ClContext& cl, const LatticeCoefficients& c, LatticeOptions options);

  // Zeroes the state (f and interfaces); the source stays.
  void clear();
  // The power deposited per node per step (3 floats per node, same layout as the volume),
  // times the coefficients' emission factors when they have them.
  void set_source(const cl::Buffer& deposit);
  void set_source(const std::vector<float>& deposit);
  // f as 3 x directions floats per node: f[(d * 3 + ch) * N + node], d = +x, -x, +y, -y, +z,
  // -z (then the diagonals of kernels/lbl/lattice18.cl).
  void set_state(const std::vector<float>& f);
  std::vector<float> state();

  // Runs at least `steps` lattice steps (whole launches of `inner` steps when blocked).
  int step(int steps);
  // Sum of f over nodes, directions and channels.
  double energy();
  // Power scattered per node per step, 3 floats per node.
  std::vector<float> irradiance();
  const cl::Buffer& irradiance_buffer() const { return irr_; }
  // The light's direction per node, m = J / phi (3 floats per node, |m| <= 1: kernels/lbl/
  // lattice.cl, lattice_flux), into `out`; the 6-direction lattice only (throws otherwise).
  void flux(cl::Buffer& out);
  size_t nodes() const { return n_; }

  // Steps until, between checks `check_every` steps apart, the relative change of the probes'
  // irradiance and of the total energy are both under `tolerance`, or `max_steps` are done.
  // `progress` (optional) hears the fraction of max_steps done after each check; it may throw.
  Convergence converge(double tolerance, int max_steps, int check_every,
                       const std::function<void(double)>& progress = {});

  // Milliseconds per lattice step over `steps` more steps, and per STREAM-like copy of the state
  // (18 floats per node) over `copies` copies; the bytes each moves through memory.
  double time_steps(int steps);
  double time_copy(int copies);
  // f in and out, coefficients (3 or 6 arrays of 3) and source, irradiance.
  double step_bytes() const {
    return double(n_) * (6 * o_.directions + (o_.directions == 6 ? 12 : 21) + 3) * sizeof(float);
  }
  double copy_bytes() const { return double(n_) * 6 * o_.directions * sizeof(float); }

 private:
  gpu::ClContext& cl_;
  LatticeOptions o_;
  int nx_, ny_, nz_;
  size_t n_;
  size_t floats() const { return 3 * size_t(o_.directions) * n_; }  // of f
  cl::Buffer pt_, ps_, w_, pt_d_, ps_d_, w_d_, src_, irr_, partial_, emit_buf_;
  std::vector<float> emit_;  // the coefficients' emission factors (empty: none)
  cl::Buffer f_[2], iface_[2];
  int cur_ = 0;  // f_[cur_] and iface_[cur_] hold the current state
  cl::Kernel step_kernel_, sum_kernel_;
  std::vector<size_t> probes_;  // node indices inside the medium
};

}  // namespace scatter::lbl
