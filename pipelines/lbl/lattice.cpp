#include "pipelines/lbl/lattice.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "pipelines/common/cl_scene.hpp"

namespace scatter::lbl {
namespace {

constexpr int kSumItems = 4096;
constexpr int kProbes = 64;

cl::Buffer device_buffer(gpu::ClContext& cl, size_t floats) {
  cl::Buffer b(cl.context(), CL_MEM_READ_WRITE, std::max<size_t>(floats, 1) * sizeof(float));
  cl.queue().enqueueFillBuffer(b, 0.f, 0, std::max<size_t>(floats, 1) * sizeof(float));
  return b;
}

}  // namespace

Lattice::Lattice(gpu::ClContext& cl, const LatticeCoefficients& c, LatticeOptions options)
    : cl_(cl), o_(options), nx_(c.nx), ny_(c.ny), nz_(c.nz), n_(size_t(c.nx) * c.ny * c.nz) {
  if (o_.blocked) {
    if (o_.block < 1 || o_.block > 8)
      throw std::invalid_argument("lattice block must be in [1, 8]");
    if (nx_ % o_.block || ny_ % o_.block || nz_ % o_.block)
      throw std::invalid_argument("lattice sides must be multiples of the block size");
    for (Edge e : o_.edges)
      if (e == Edge::Periodic)
        throw std::invalid_argument("the blocked lattice has no periodic edges");
    if (o_.inner < 1) throw std::invalid_argument("lattice inner steps must be at least 1");
  }
  if (o_.directions != 6 && o_.directions != 18)
    throw std::invalid_argument("lattice directions must be 6 or 18");
  if (o_.directions == 18 && o_.blocked)
    throw std::invalid_argument("the 18-direction lattice has no blocked form");
  if (!c.emit.empty() && c.emit.size() != c.pt.size())
    throw std::invalid_argument("the lattice's emission factors must hold 3 floats per node");
  // The emission factor scales what a node scatters on (ps) and, in set_source, its source.
  auto emitted = [&](const std::vector<float>& ps) {
    std::vector<float> out = ps;
    for (size_t i = 0; i < c.emit.size(); ++i) out[i] *= c.emit[i];
    return out;
  };
  pt_ = upload(cl, c.pt);
  ps_ = upload(cl, emitted(c.ps));
  w_ = upload(cl, c.w);
  if (!c.emit.empty()) {
    emit_ = c.emit;
    emit_buf_ = upload(cl, c.emit);
  }
  if (o_.directions == 18) {
    if (c.pt_diag.size() != c.pt.size() || c.ps_diag.size() != c.pt.size() ||
        c.w_diag.size() != c.pt.size())
      throw std::invalid_argument("the 18-direction lattice needs the diagonal coefficients");
    pt_d_ = upload(cl, c.pt_diag);
    ps_d_ = upload(cl, emitted(c.ps_diag));
    w_d_ = upload(cl, c.w_diag);
  }
  src_ = device_buffer(cl, 3 * n_);
  irr_ = device_buffer(cl, 3 * n_);
  partial_ = device_buffer(cl, kSumItems);
  for (auto& f : f_) f = device_buffer(cl, floats());
  size_t blocks = o_.blocked ? n_ / (size_t(o_.block) * o_.block * o_.block) : 0;
  for (auto& i : iface_) i = device_buffer(cl, blocks * 6 * o_.block * o_.block * 3);
  std::string defines = o_.blocked ? "-DLBL_B=" + std::to_string(o_.block) : "";
  cl::Program& program = cl.program({"kernels/lbl/lattice.cl"}, defines);
  if (o_.directions == 18)
    step_kernel_ = cl::Kernel(cl.program({"kernels/lbl/lattice18.cl"}), "lattice18_step");
  else
    step_kernel_ = cl::Kernel(program, o_.blocked ? "lattice_blocked" : "lattice_step");
  sum_kernel_ = cl::Kernel(program, "partial_sums");
  // Probes: nodes that scatter, spread evenly through the grid's order.
  std::vector<size_t> medium;
  for (size_t i = 0; i < n_; ++i)
    if (c.w[3 * i] > 0 || c.w[3 * i + 1] > 0 || c.w[3 * i + 2] > 0) medium.push_back(i);
  for (int p = 0; p < kProbes && !medium.empty(); ++p)
    probes_.push_back(medium[(medium.size() * (2 * p + 1)) / (2 * kProbes)]);
  cl.queue().finish();
}

void Lattice::clear() {
  for (auto& f : f_) cl_.queue().enqueueFillBuffer(f, 0.f, 0, floats() * sizeof(float));
  for (auto& i : iface_) {
    size_t bytes = i.getInfo<CL_MEM_SIZE>();
    cl_.queue().enqueueFillBuffer(i, 0.f, 0, bytes);
  }
  cl_.queue().enqueueFillBuffer(irr_, 0.f, 0, 3 * n_ * sizeof(float));
}

void Lattice::set_source(const cl::Buffer& deposit) {
  cl_.queue().enqueueCopyBuffer(deposit, src_, 0, 0, 3 * n_ * sizeof(float));
  if (emit_.empty()) return;
  cl::Kernel k(cl_.program({"kernels/lbl/lattice.cl"}), "scale_by");
  gpu::set_args(k, src_, emit_buf_);
  cl_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(3 * n_));
}

void Lattice::set_source(const std::vector<float>& deposit) {
  if (deposit.size() != 3 * n_)
    throw std::invalid_argument("lattice source must hold 3 floats per node");
  std::vector<float> src = deposit;
  for (size_t i = 0; i < emit_.size(); ++i) src[i] *= emit_[i];
  cl_.queue().enqueueWriteBuffer(src_, CL_TRUE, 0, src.size() * sizeof(float), src.data());
}

void Lattice::set_state(const std::vector<float>& f) {
  if (f.size() != floats())
    throw std::invalid_argument("lattice state must hold 3 floats per node and direction");
  cl_.queue().enqueueWriteBuffer(f_[cur_], CL_TRUE, 0, f.size() * sizeof(float), f.data());
  if (!o_.blocked) return;
  cl::Kernel k(cl_.program({"kernels/lbl/lattice.cl"}, "-DLBL_B=" + std::to_string(o_.block)),
               "lattice_interfaces");
  gpu::set_args(k, nx_, ny_, nz_, f_[cur_], iface_[cur_]);
  cl_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(nx_, ny_, nz_),
                                   cl::NDRange(o_.block, o_.block, o_.block));
  cl_.queue().finish();
}

std::vector<float> Lattice::state() {
  std::vector<float> f(floats());
  cl_.queue().enqueueReadBuffer(f_[cur_], CL_TRUE, 0, f.size() * sizeof(float), f.data());
  return f;
}

int Lattice::step(int steps) {
  const int per_launch = o_.blocked ? o_.inner : 1;
  int done = 0;
  const int ex = int(o_.edges[0]), ey = int(o_.edges[1]), ez = int(o_.edges[2]);
  while (done < steps) {
    int next = 1 - cur_;
    if (o_.blocked) {
      gpu::set_args(step_kernel_, nx_, ny_, nz_, ex, ey, ez, pt_, ps_, w_, src_, f_[cur_], f_[next],
                    irr_, iface_[cur_], iface_[next], o_.inner);
      cl_.queue().enqueueNDRangeKernel(step_kernel_, cl::NullRange, cl::NDRange(nx_, ny_, nz_),
                                       cl::NDRange(o_.block, o_.block, o_.block));
    } else if (o_.directions == 18) {
      gpu::set_args(step_kernel_, nx_, ny_, nz_, ex, ey, ez, pt_, ps_, w_, pt_d_, ps_d_, w_d_, src_,
                    f_[cur_], f_[next], irr_);
      cl_.queue().enqueueNDRangeKernel(step_kernel_, cl::NullRange, cl::NDRange(nx_, ny_, nz_));
    } else {
      gpu::set_args(step_kernel_, nx_, ny_, nz_, ex, ey, ez, pt_, ps_, w_, src_, f_[cur_], f_[next],
                    irr_);
      cl_.queue().enqueueNDRangeKernel(step_kernel_, cl::NullRange, cl::NDRange(nx_, ny_, nz_));
    }
    cur_ = next;
    done += per_launch;
  }
  return done;
}

double Lattice::energy() {
  gpu::set_args(sum_kernel_, f_[cur_], cl_ulong(floats()), partial_);
  cl_.queue().enqueueNDRangeKernel(sum_kernel_, cl::NullRange, cl::NDRange(kSumItems));
  std::vector<float> partial(kSumItems);
  cl_.queue().enqueueReadBuffer(partial_, CL_TRUE, 0, kSumItems * sizeof(float), partial.data());
  double total = 0;
  for (float p : partial) total += p;
  return total;
}

void Lattice::flux(cl::Buffer& out) {
  if (o_.directions != 6) throw std::invalid_argument("the lattice's flux needs 6 directions");
  cl::Kernel k(cl_.program({"kernels/lbl/lattice.cl"}), "lattice_flux");
  gpu::set_args(k, nx_, ny_, nz_, int(o_.edges[0]), int(o_.edges[1]), int(o_.edges[2]), f_[cur_],
                out);
  cl_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(nx_, ny_, nz_));
}

std::vector<float> Lattice::irradiance() {
  std::vector<float> irr(3 * n_);
  cl_.queue().enqueueReadBuffer(irr_, CL_TRUE, 0, irr.size() * sizeof(float), irr.data());
  return irr;
}

Convergence Lattice::converge(double tolerance, int max_steps, int check_every,
                              const std::function<void(double)>& progress) {
  Convergence c;
  check_every = std::max(check_every, 1);
  auto probe_values = [&] {
    std::vector<float> irr = irradiance();
    std::vector<double> v;
    for (size_t p : probes_)
      for (int ch = 0; ch < 3; ++ch) v.push_back(irr[3 * p + ch]);
    return v;
  };
  std::vector<double> before = probe_values();
  double energy_before = energy();
  while (c.steps < max_steps) {
    c.steps += step(std::min(check_every, max_steps - c.steps));
    if (progress) progress(double(c.steps) / max_steps);  // may throw to stop (a cancelled render)
    std::vector<double> now = probe_values();
    double energy_now = energy();
    double scale = 0;
    for (double v : now) scale = std::max(scale, std::abs(v));
    // Probes far below the brightest one change by relative amounts that do not show.
    double change = 0;
    for (size_t i = 0; i < now.size(); ++i)
      change = std::max(
          change, std::abs(now[i] - before[i]) / std::max({std::abs(now[i]), 1e-3 * scale, 1e-30}));
    if (energy_now > 0 || energy_before > 0)
      change = std::max(change,
                        std::abs(energy_now - energy_before) / std::max(energy_now, energy_before));
    c.change = change;
    if (!(std::isfinite(change))) break;
    if (change < tolerance) {
      c.converged = true;
      break;
    }
    before = std::move(now);
    energy_before = energy_now;
  }
  return c;
}

double Lattice::time_steps(int steps) {
  cl_.queue().finish();
  auto t0 = std::chrono::steady_clock::now();
  int done = step(steps);
  cl_.queue().finish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
         done;
}

double Lattice::time_copy(int copies) {
  cl::Kernel k(cl_.program({"kernels/lbl/lattice.cl"}), "stream_copy");
  // Copies between the two state buffers: the spare one is overwritten by the next step anyway.
  gpu::set_args(k, f_[cur_], f_[1 - cur_]);
  cl_.queue().finish();
  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < copies; ++i)
    cl_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(floats() / 4));
  cl_.queue().finish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
         copies;
}

}  // namespace scatter::lbl
