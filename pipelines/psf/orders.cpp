#include "pipelines/psf/orders.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "pipelines/psf/psf_model.hpp"

namespace scatter::psf {
namespace {

cl::NDRange range(const cl_int4& l) {
  return cl::NDRange(size_t(l.s[1]), size_t(l.s[2]), size_t(l.s[3]));
}

// Per-channel Gaussian taps (float4 each, the fourth zero) of standard deviations `sigma` in
// voxels; a channel whose sigma is below a twentieth of a voxel keeps the centre only.
std::vector<cl_float4> channel_taps(const std::array<double, 3>& sigma) {
  std::vector<std::vector<float>> per(3);
  size_t radius = 1;
  for (int c = 0; c < 3; ++c) {
    per[c] = sigma[c] < 0.05 ? std::vector<float>{1.f} : gaussian_taps(sigma[c]);
    radius = std::max(radius, per[c].size() - 1);
  }
  std::vector<cl_float4> taps(radius + 1, cl_float4{{0, 0, 0, 0}});
  for (int c = 0; c < 3; ++c)
    for (size_t d = 0; d < per[c].size(); ++d) taps[d].s[c] = per[c][d];
  return taps;
}

std::array<double, 3> channel_sums(cl::CommandQueue& queue, const cl::Buffer& b, size_t n) {
  std::vector<cl_float4> host(n);
  queue.enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(cl_float4), host.data());
  std::array<double, 3> s{};
  for (const cl_float4& v : host)
    for (int c = 0; c < 3; ++c) s[c] += v.s[c];
  return s;
}

}  // namespace

double calibrated_drift(double g) {
  return std::min(0.5, 2.5 * (1 - g));
}

int orders_level(const OrderParams& params, float voxel, int levels) {
  if (params.level >= 0) return std::min(params.level, levels - 1);
  const double c =
      std::max({params.mean_sigma_t[0], params.mean_sigma_t[1], params.mean_sigma_t[2]});
  const double spread = c > 0 ? std::sqrt(order_flight(params.g, 1).variance) / c : 1e30;
  int level = 0;
  while (level < 3 && level + 1 < levels && voxel * std::ldexp(1.0, level + 1) <= spread / 3)
    ++level;
  return level;
}

std::vector<FlightGaussian> flight_mixture(int flights) {
  if (flights == 1) return {{std::sqrt(2.0 / 3.0), 1.0}};
  return {{0.1, 0.2025}, {0.3625, 0.4466}, {1.3141, 0.3509}};
}

namespace {

// One order's flight on the orders' grid: its Gaussians' per-channel taps (each sigma^2 / (2/3)
// of the flight's variance; order 1 less what the pyramid's level already holds).
struct Flight {
  std::vector<cl::Buffer> taps;
  std::vector<int> radius;
  std::array<double, 3> variance{}, drift{};  // world units (squared), per channel
};

Flight make_flight(gpu::ClContext& cl, const OrderParams& params, int m, double stored,
                   double cell) {
  Flight fl;
  const OrderFlight f = order_flight(params.g, m);
  for (int c = 0; c < 3; ++c) {
    const double st = params.mean_sigma_t[c];
    if (st <= 0) continue;
    fl.variance[c] = f.variance / (st * st);
    fl.drift[c] = params.drift * f.drift / st;
  }
  for (const FlightGaussian& mix : flight_mixture(params.flights)) {
    std::array<double, 3> sd{};
    for (int c = 0; c < 3; ++c) {
      const double var =
          1.5 * mix.sigma * mix.sigma * fl.variance[c] - (m == 1 ? stored * stored : 0.0);
      sd[c] = std::sqrt(std::max(var, 0.0)) / cell;
    }
    std::vector<cl_float4> taps = channel_taps(sd);
    fl.taps.emplace_back(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                         taps.size() * sizeof(cl_float4), taps.data());
    fl.radius.push_back(static_cast<int>(taps.size()) - 1);
  }
  return fl;
}

cl_float4 float4_of(const std::array<double, 3>& v) {
  return cl_float4{
      {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]), 0}};
}

// Whether the normalisation made for flight `a` serves flight `b`: variances within 1 % and
// drifts within a twentieth of a cell.
bool same_flight(const Flight& a, const Flight& b, double cell) {
  for (int c = 0; c < 3; ++c) {
    if (std::fabs(b.variance[c] - a.variance[c]) > 0.01 * a.variance[c]) return false;
    if (std::fabs(b.drift[c] - a.drift[c]) > 0.05 * cell) return false;
  }
  return true;
}

}  // namespace

Orders build_orders(gpu::ClContext& cl, const ClMedium& medium, const cl::Buffer& occupancy,
                    const Pyramid& pyramid, const cl::Buffer& lights, int light,
                    const OrderParams& params) {
  auto start = std::chrono::steady_clock::now();
  Orders o;
  o.flights = params.flights;
  o.tail = params.tail;
  o.drift = params.drift;
  o.conserve = params.conserve;
  o.level = orders_level(params, medium.voxel, static_cast<int>(pyramid.layout.size()));
  const cl_int4 l = pyramid.layout[o.level];
  o.nx = l.s[1], o.ny = l.s[2], o.nz = l.s[3];
  o.cell = medium.voxel * float(1 << o.level);
  const size_t n = size_t(o.nx) * o.ny * o.nz, bytes = n * sizeof(cl_float4);
  const int count = static_cast<int>(n);
  auto& queue = cl.queue();
  auto buffer = [&](size_t b) { return cl::Buffer(cl.context(), CL_MEM_READ_WRITE, b); };
  cl::Buffer q = buffer(bytes), a = buffer(bytes), b = buffer(bytes), acc = buffer(bytes),
             phi = buffer(bytes), sigma = buffer(bytes);
  o.bands = buffer(4 * bytes);
  queue.enqueueFillBuffer(o.bands, 0.f, 0, 4 * bytes);
  queue.enqueueCopyBuffer(pyramid.data, q, size_t(l.s[0]) * sizeof(cl_float4), 0, bytes);
  cl::Kernel blur(program(cl), "blur_axis"), step(program(cl), "order_step"),
      add(program(cl), "add_scaled"), tail(program(cl), "add_tail");
  const cl_float4 c_mean = float4_of(params.mean_sigma_t);
  // conserve: the coarse c_eff and occupancy, their blurs by the current flight, the scale.
  cl::Buffer ceff, occ, n_blur, e_blur, scale;
  if (params.conserve) {
    ceff = buffer(bytes), occ = buffer(bytes), n_blur = buffer(bytes), e_blur = buffer(bytes),
    scale = buffer(bytes);
    cl::Kernel coarse(program(cl), "coarse_collision");
    gpu::set_args(coarse, medium.sigma_s, medium.sigma_t, occupancy, medium.nx, medium.ny,
                  medium.nz, o.level, o.cell, sigma, ceff, occ, o.nx, o.ny, o.nz);
    queue.enqueueNDRangeKernel(coarse, cl::NullRange, range(l));
  } else {
    cl::Kernel coarse(program(cl), "coarse_sigma");
    gpu::set_args(coarse, medium.sigma_s, medium.sigma_t, medium.nx, medium.ny, medium.nz, o.level,
                  c_mean, sigma, o.nx, o.ny, o.nz);
    queue.enqueueNDRangeKernel(coarse, cl::NullRange, range(l));
  }
  // The flight's Gaussians of `in`, summed with their weights into `out`.
  const std::vector<FlightGaussian> mixture = flight_mixture(params.flights);
  auto blur_flight = [&](const Flight& fl, const cl::Buffer& in, cl::Buffer& out) {
    for (size_t i = 0; i < mixture.size(); ++i) {
      const cl::Buffer* from = &in;
      cl::Buffer* bufs[2] = {&a, &b};
      for (int axis = 0; axis < 3; ++axis) {
        gpu::set_args(blur, *from, o.nx, o.ny, o.nz, axis, fl.taps[i], fl.radius[i],
                      *bufs[axis % 2]);
        queue.enqueueNDRangeKernel(blur, cl::NullRange, range(l));
        from = bufs[axis % 2];
      }
      gpu::set_args(add, out, *from, static_cast<float>(mixture[i].weight), i == 0 ? 1 : 0, count);
      queue.enqueueNDRangeKernel(add, cl::NullRange, cl::NDRange(n));
    }
  };
  const std::array<double, 3> first = channel_sums(queue, q, n);
  // The pyramid's level already holds the source blurred by its stored width.
  const double stored = stored_width(o.level) * medium.voxel;
  std::array<double, 3> before = first;  // the source's power 4 orders ago
  double last_lambda = -1;
  Flight normalised;  // the flight the current scale was made for
  for (int m = 1; m <= params.max_orders; ++m) {
    const Flight fl = make_flight(cl, params, m, stored, o.cell);
    if (params.conserve) {
      if (o.normalisations == 0 || !same_flight(normalised, fl, o.cell)) {
        // The normalisation's kernel is the flight's own, without order 1's stored part.
        const Flight full = m == 1 ? make_flight(cl, params, m, 0, o.cell) : fl;
        blur_flight(full, ceff, n_blur);
        blur_flight(full, occ, e_blur);
        cl::Kernel k(program(cl), "order_scale");
        gpu::set_args(k, n_blur, e_blur, o.nx, o.ny, o.nz, medium.origin, o.cell, lights, light,
                      float4_of(fl.drift), c_mean, scale);
        queue.enqueueNDRangeKernel(k, cl::NullRange, range(l));
        normalised = fl;
        ++o.normalisations;
      }
      cl::Kernel k(program(cl), "scale_by");
      gpu::set_args(k, q, scale, count);
      queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(n));
    }
    blur_flight(fl, q, acc);
    cl_float4 inv_c{{0, 0, 0, 0}};
    for (int c = 0; c < 3; ++c)
      if (params.mean_sigma_t[c] > 0) inv_c.s[c] = static_cast<float>(1 / params.mean_sigma_t[c]);
    const float gn = static_cast<float>(std::pow(params.g, m + 1));
    gpu::set_args(step, acc, sigma, o.nx, o.ny, o.nz, medium.origin, o.cell, lights, light,
                  float4_of(fl.drift), inv_c, std::min(m - 1, 2), cl_float4{{gn, gn, gn, 0}},
                  o.bands, q, phi);
    queue.enqueueNDRangeKernel(step, cl::NullRange, range(l));
    o.count = m;
    if (m % 4 != 0) continue;
    const std::array<double, 3> now = channel_sums(queue, q, n);
    bool done = true;
    for (int c = 0; c < 3; ++c) done = done && now[c] <= params.tolerance * first[c];
    if (done) break;
    // The decay per order over the last 4 (the channel that decays slowest); once it holds
    // steady, the rest is a geometric series of this order's fluence.
    double lambda = 0;
    for (int c = 0; c < 3; ++c)
      if (before[c] > 0) lambda = std::max(lambda, std::pow(now[c] / before[c], 0.25));
    before = now;
    if (params.tail && m >= 12 && lambda < 1 && std::fabs(lambda - last_lambda) < 0.002) {
      cl_float4 rest{{0, 0, 0, 0}}, moment{{0, 0, 0, 0}};
      const double gl = params.g * lambda;
      for (int c = 0; c < 3; ++c) {
        rest.s[c] = static_cast<float>(lambda / (1 - lambda));
        moment.s[c] = static_cast<float>(gn * gl / (1 - gl));
      }
      gpu::set_args(tail, o.bands, phi, rest, moment, count);
      queue.enqueueNDRangeKernel(tail, cl::NullRange, cl::NDRange(n));
      o.lambda = lambda;
      break;
    }
    last_lambda = lambda;
  }
  queue.finish();
  o.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return o;
}

}  // namespace scatter::psf
