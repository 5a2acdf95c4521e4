#include "pipelines/single/single_bake.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "pipelines/single/bake_support.hpp"
#include "pipelines/single/sampling.hpp"
#include "pipelines/single/sh.hpp"

namespace scatter {
using namespace single_detail;
namespace {

const std::vector<std::string> kProgram = with_cl_library({"kernels/single/bake.cl"});
constexpr float kDepthClamp = 20;  // exp(-20) ~ 2e-9: deeper is dark either way
constexpr int kMaxShell = kSingleGridMargin - 1;

}  // namespace

void SingleBakeParams::check() const {
  if (split > 0 && split < 1.5)
    throw ValidationError("settings.split", "split must be 0 (off) or at least 1.5");
  // The elimination keeps ~25 neighbours per candidate: bound the candidates' memory (~1 GB).
  if (double(samples) * candidates > 2.5e6)
    throw ValidationError("settings.candidates",
                          "samples x candidates must not exceed 2500000 (got " +
                              std::to_string(samples) + " x " + std::to_string(candidates) + ")");
}

std::vector<float> first_moment(gpu::ClContext& cl, const VoxelGrid& grid,
                                const std::vector<Vec3>& dirs,
                                const std::function<void(double)>& progress) {
  const size_t voxels = grid.count();
  std::vector<float> sigma(voxels);
  for (size_t v = 0; v < voxels; ++v)
    sigma[v] = (grid.sigma_s[3 * v] + grid.sigma_a[3 * v] + grid.sigma_s[3 * v + 1] +
                grid.sigma_a[3 * v + 1] + grid.sigma_s[3 * v + 2] + grid.sigma_a[3 * v + 2]) /
               3;
  cl::Buffer d_sigma = upload(cl, sigma);
  std::vector<float> zeros(3 * voxels, 0.f);
  cl::Buffer moment(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                    zeros.size() * sizeof(float), zeros.data());
  cl::Kernel kernel(cl.program(kProgram), "sweep_slice");
  const int dims[3] = {grid.nx, grid.ny, grid.nz};
  const double d_omega = 4 * std::numbers::pi / double(dirs.size());
  auto& queue = cl.queue();
  int groups_done = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {1, -1}) {
      std::vector<float> params, moments;
      for (const Vec3& w : dirs) {
        double c[3] = {w.x, w.y, w.z};
        double a = std::abs(c[axis]);
        int major = std::abs(c[0]) >= std::abs(c[1]) && std::abs(c[0]) >= std::abs(c[2])
                        ? 0
                        : (std::abs(c[1]) >= std::abs(c[2]) ? 1 : 2);
        if (major != axis || (c[axis] >= 0 ? 1 : -1) != sign) continue;
        int ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
        params.insert(params.end(),
                      {float(c[ua] / a), float(c[va] / a), float(grid.voxel / a), 0.f});
        moments.insert(moments.end(),
                       {float(w.x * d_omega), float(w.y * d_omega), float(w.z * d_omega), 0.f});
      }
      if (params.empty()) {
        ++groups_done;
        continue;
      }
      const int count = static_cast<int>(params.size() / 4);
      const int n = dims[axis];
      const int nu = axis == 0 ? grid.ny : grid.nx, nv = axis == 2 ? grid.ny : grid.nz;
      const size_t slice_floats = size_t(count) * nu * nv;
      cl::Buffer d_params = upload(cl, params), d_moments = upload(cl, moments);
      cl::Buffer a(cl.context(), CL_MEM_READ_WRITE, slice_floats * sizeof(float));
      cl::Buffer b(cl.context(), CL_MEM_READ_WRITE, slice_floats * sizeof(float));
      // Downstream first: the slice nearest the exit has no upstream neighbour inside the grid.
      for (int step = 0; step < n; ++step) {
        int k = sign > 0 ? n - 1 - step : step;
        cl::Buffer& prev = (step % 2) ? a : b;
        cl::Buffer& cur = (step % 2) ? b : a;
        gpu::set_args(kernel, d_sigma, grid.nx, grid.ny, grid.nz, axis, k, k + sign, d_params,
                      d_moments, count, prev, cur, moment);
        queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(nu), size_t(nv)));
      }
      queue.finish();
      if (progress) progress(++groups_done / 6.0);
    }
  std::vector<float> out(3 * voxels);
  queue.enqueueReadBuffer(moment, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  return out;
}

std::vector<float> divergence(const VoxelGrid& g, const std::vector<float>& T) {
  std::vector<float> rho(g.count(), 0.f);
  auto at = [&](int i, int j, int k, int c) -> double {
    i = std::clamp(i, 0, g.nx - 1);
    j = std::clamp(j, 0, g.ny - 1);
    k = std::clamp(k, 0, g.nz - 1);
    return T[3 * g.index(i, j, k) + c];
  };
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        size_t v = g.index(i, j, k);
        if (g.occupancy[v] <= 0) continue;
        double div = (at(i + 1, j, k, 0) - at(i - 1, j, k, 0)) +
                     (at(i, j + 1, k, 1) - at(i, j - 1, k, 1)) +
                     (at(i, j, k + 1, 2) - at(i, j, k - 1, 2));
        rho[v] = static_cast<float>(std::abs(div) / (2 * g.voxel));
      }
  return rho;
}

namespace {

// The grid's extinction and the directions on the device, uploaded once for all chunks.
struct DepthTables {
  cl::Buffer sigma_t, dirs;
  DepthTables(gpu::ClContext& cl, const VoxelGrid& grid, const std::vector<Vec3>& directions) {
    std::vector<float> st(grid.sigma_s.size());
    for (size_t i = 0; i < st.size(); ++i) st[i] = grid.sigma_s[i] + grid.sigma_a[i];
    std::vector<float> flat;
    for (const Vec3& d : directions) flat.insert(flat.end(), {float(d.x), float(d.y), float(d.z)});
    sigma_t = upload(cl, st);
    dirs = upload(cl, flat);
  }
};

std::vector<float> sample_depths(gpu::ClContext& cl, const VoxelGrid& grid,
                                 const DepthTables& tables, const std::vector<float>& positions,
                                 int n) {
  const int samples = static_cast<int>(positions.size() / 3);
  std::vector<float> out(size_t(samples) * n * 3);
  if (samples == 0) return out;
  cl::Buffer d_pos = upload(cl, positions);
  const cl::Buffer& d_sigma = tables.sigma_t;
  const cl::Buffer& d_dirs = tables.dirs;
  cl::Buffer d_out(cl.context(), CL_MEM_WRITE_ONLY, out.size() * sizeof(float));
  cl::Kernel k(cl.program(kProgram), "sample_depths");
  cl_float3 origin{{float(grid.origin.x), float(grid.origin.y), float(grid.origin.z)}};
  gpu::set_args(k, origin, float(grid.voxel), grid.nx, grid.ny, grid.nz, d_sigma, d_pos, samples,
                d_dirs, n, d_out);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(size_t(samples), size_t(n)));
  cl.queue().enqueueReadBuffer(d_out, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  return out;
}

}  // namespace

std::vector<float> sample_depths(gpu::ClContext& cl, const VoxelGrid& grid,
                                 const std::vector<float>& positions,
                                 const std::vector<Vec3>& dirs) {
  return sample_depths(cl, grid, DepthTables(cl, grid, dirs), positions,
                       static_cast<int>(dirs.size()));
}

double gaussian_sum(const SingleBake& b, const Vec3& p) {
  double s = 0;
  for (int i = 0; i < b.count; ++i) {
    Vec3 c{b.position[3 * i], b.position[3 * i + 1], b.position[3 * i + 2]};
    double sg = b.sigma[i], r2 = dot(p - c, p - c);
    if (r2 > kCutoff * kCutoff * sg * sg) continue;
    if (!b.plane.empty() &&
        dot(Vec3{b.plane[4 * i], b.plane[4 * i + 1], b.plane[4 * i + 2]}, p) > b.plane[4 * i + 3])
      continue;
    s += b.weight[i] * std::exp(-r2 / (2 * sg * sg));
  }
  return s;
}

SingleBake bake_single(gpu::ClContext& cl, const VoxelGrid& g, const SingleBakeParams& p,
                       const BakeProgress& progress) {
  auto report = [&](const char* stage, double f) {
    if (progress) progress(stage, f);
  };
  SingleBake bake;
  bake.params = p;
  StageClock clock(bake.timings);
  const size_t voxels = g.count();
  const double dv = g.voxel * g.voxel * g.voxel;

  // 1. Direction-dependent optical depth, folded into its first moment.
  report("ddod", 0);
  const std::vector<Vec3> dirs = sphere_directions(p.directions);
  std::vector<float> moment = first_moment(cl, g, dirs, [&](double f) { report("ddod", f); });
  clock.stop("ddod");
  report("ddod", 1);

  // 2. Sampling density.
  std::vector<float> rho = divergence(g, moment);
  clock.stop("divergence");
  report("divergence", 1);

  // Optionally (density_guide) also where the extinction changes inside the medium, such as
  // between layers: rho += rho_95 * |grad sigma_t| / its 95th percentile, over voxels whose six
  // neighbours are all medium (the surface is div T's already).
  if (p.density_guide) {
    std::vector<float> grad(voxels, 0.f), found;
    auto st = [&](size_t v) { return extinction(g, v); };
    for (int k = 1; k + 1 < g.nz; ++k)
      for (int j = 1; j + 1 < g.ny; ++j)
        for (int i = 1; i + 1 < g.nx; ++i) {
          size_t v = g.index(i, j, k);
          size_t n[6] = {g.index(i - 1, j, k), g.index(i + 1, j, k), g.index(i, j - 1, k),
                         g.index(i, j + 1, k), g.index(i, j, k - 1), g.index(i, j, k + 1)};
          bool interior = g.occupancy[v] >= 1;
          for (size_t u : n) interior = interior && g.occupancy[u] >= 1;
          if (!interior) continue;
          double gx = st(n[1]) - st(n[0]), gy = st(n[3]) - st(n[2]), gz = st(n[5]) - st(n[4]);
          grad[v] = static_cast<float>(std::sqrt(gx * gx + gy * gy + gz * gz) / (2 * g.voxel));
          found.push_back(grad[v]);
        }
    std::vector<float> r;
    for (size_t v = 0; v < voxels; ++v)
      if (g.occupancy[v] > 0) r.push_back(rho[v]);
    if (!found.empty() && !r.empty()) {
      std::sort(found.begin(), found.end());
      std::sort(r.begin(), r.end());
      double g95 = found[found.size() * 19 / 20], r95 = r[r.size() * 19 / 20];
      if (g95 > 0)
        for (size_t v = 0; v < voxels; ++v) rho[v] += static_cast<float>(r95 * grad[v] / g95);
    }
  }

  // 3. Relative radius q in [0.5, 2]^adapt from rho (high rho: dense, small radius).
  std::vector<float> medium_rho;
  for (size_t v = 0; v < voxels; ++v)
    if (g.occupancy[v] > 0) medium_rho.push_back(rho[v]);
  if (medium_rho.empty()) throw ValidationError("scene", "the object holds no medium to sample");
  std::sort(medium_rho.begin(), medium_rho.end());
  const double lo = medium_rho[medium_rho.size() / 20],
               hi = medium_rho[medium_rho.size() * 19 / 20];
  const bool constant = !(hi - lo > 1e-6 * std::max(hi, 1e-30));
  std::vector<float> q(voxels, 1.f);
  for (size_t v = 0; v < voxels; ++v)
    if (!constant)
      q[v] = static_cast<float>(
          std::pow(2.0 - 1.5 * std::clamp((rho[v] - lo) / (hi - lo), 0.0, 1.0), p.adapt));

  // The sampled region: the medium plus a shell of `shell` voxels around it, each shell voxel
  // taking the smallest radius of its neighbours inward. Gaussians centred in the shell keep the
  // sum of Gaussians near one up to the surface (the mesh's depth clips what lies outside), where
  // single scattering is strongest; without them the sum falls to about half at the surface.
  double medium_volume = 0;
  float q_min = 2;
  for (size_t v = 0; v < voxels; ++v)
    if (g.occupancy[v] > 0) {
      medium_volume += dv / (double(q[v]) * q[v] * q[v]);
      q_min = std::min(q_min, q[v]);
    }
  const double r_estimate = std::cbrt(medium_volume / (4 * std::sqrt(2.0) * p.samples));
  const double sigma_least = std::max(p.radius * 2 * r_estimate * q_min, kMinSigmaVoxels * g.voxel);
  const int shell = std::clamp(int(std::ceil(2.5 * sigma_least / g.voxel)), 1, kMaxShell);
  // anchor: for a shell voxel, a medium voxel it was reached from; its samples read their optical
  // depth there (shifted by the same offset), since from outside a convex surface a grazing light
  // or view direction misses the medium that the Gaussian covers inside.
  std::vector<uint8_t> layer(voxels, 255);
  std::vector<size_t> anchor(voxels);
  for (size_t v = 0; v < voxels; ++v) {
    anchor[v] = v;
    if (g.occupancy[v] > 0) layer[v] = 0;
  }
  for (int d = 1; d <= shell; ++d)
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
          size_t v = g.index(i, j, k);
          if (layer[v] != 255) continue;
          const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                                {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
          for (const auto& n : nb) {
            if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= g.nx || n[1] >= g.ny || n[2] >= g.nz)
              continue;
            size_t u = g.index(n[0], n[1], n[2]);
            if (layer[u] != d - 1) continue;
            if (layer[v] == 255 || q[u] < q[v]) {
              q[v] = q[u];
              anchor[v] = anchor[u];
            }
            layer[v] = static_cast<uint8_t>(d);
          }
        }
  std::vector<double> cdf(voxels + 1, 0.0);
  double volume = 0;
  for (size_t v = 0; v < voxels; ++v) {
    double w = layer[v] <= shell ? dv / (double(q[v]) * q[v] * q[v]) : 0.0;
    volume += w;
    cdf[v + 1] = cdf[v] + w;
  }
  const int m = p.samples * p.candidates;
  std::vector<Vec3> candidates(m);
  std::vector<float> cq(m);
  std::vector<size_t> cvoxel(m);
  std::mt19937_64 rng(p.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int c = 0; c < m; ++c) {
    double x = uni(rng) * cdf.back();
    size_t v =
        std::min(voxels - 1, size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin()) - 1);
    int i = int(v % g.nx), j = int((v / g.nx) % g.ny), k = int(v / (size_t(g.nx) * g.ny));
    candidates[c] = g.origin + Vec3{i + uni(rng), j + uni(rng), k + uni(rng)} * g.voxel;
    cq[c] = q[v];
    cvoxel[c] = v;
  }
  report("sampling", 0.2);
  EliminationResult kept = eliminate_samples(candidates, cq, volume, p.samples,
                                             [&](double f) { report("sampling", 0.2 + 0.8 * f); });
  bake.count = p.samples;
  // In progressive order: the first half, quarter, ... of the samples are Poisson-disk sets
  // themselves (sample_fraction splats such a prefix while the user drags).
  {
    std::vector<Vec3> kept_points;
    std::vector<float> kept_q;
    for (int c : kept.kept) {
      kept_points.push_back(candidates[size_t(c)]);
      kept_q.push_back(cq[size_t(c)]);
    }
    std::vector<int> order = progressive_order(kept_points, kept_q, volume);
    std::vector<int> ordered(order.size());
    for (size_t k = 0; k < order.size(); ++k) ordered[k] = kept.kept[size_t(order[k])];
    kept.kept = std::move(ordered);
  }
  bake.position.reserve(3 * size_t(bake.count));
  std::vector<float>& depth_position = bake.depth_at;
  auto voxel_centre = [&](size_t v) {
    return g.center(int(v % g.nx), int((v / g.nx) % g.ny), int(v / (size_t(g.nx) * g.ny)));
  };
  for (int c : kept.kept) {
    const Vec3& x = candidates[c];
    bake.position.insert(bake.position.end(), {float(x.x), float(x.y), float(x.z)});
    Vec3 xd = x + (voxel_centre(anchor[cvoxel[c]]) - voxel_centre(cvoxel[c]));
    depth_position.insert(depth_position.end(), {float(xd.x), float(xd.y), float(xd.z)});
    // Local spacing: twice the Poisson radius, scaled by the local relative radius; sigma at
    // least kMinSigmaVoxels of a voxel.
    bake.sigma.push_back(static_cast<float>(
        std::max(p.radius * 2 * kept.base_radius * cq[c], kMinSigmaVoxels * g.voxel)));
  }
  clock.stop("sampling");
  report("sampling", 1);

  // 4. Gaussian weights and each sample's sigma_s (pipelines/single/single_gaussians.cpp).
  make_gaussians(g, layer, shell, p, bake, [&](double f) { report("gaussians", f); });
  const int n = bake.count;
  clock.stop("gaussians");
  report("gaussians", 1);

  // 5. Spherical harmonics of the optical depth (or transmittance) per sample and channel, in
  //    chunks that keep the depth table under ~64 MB.
  const int nc = sh_count(p.sh_order);
  std::vector<float> basis(dirs.size() * nc);
  for (size_t k = 0; k < dirs.size(); ++k) sh_basis(dirs[k], p.sh_order, &basis[k * nc]);
  bake.sh.assign(size_t(n) * 3 * nc, 0.f);
  const size_t chunk = std::clamp<size_t>((16u << 20) / (dirs.size() * 3), 1, std::max(1, n / 8));
  const double w = 4 * std::numbers::pi / double(dirs.size());
  const DepthTables tables(cl, g, dirs);
  for (size_t first = 0; first < size_t(n); first += chunk) {
    size_t last = std::min(size_t(n), first + chunk);
    std::vector<float> part(depth_position.begin() + 3 * first, depth_position.begin() + 3 * last);
    std::vector<float> tau = sample_depths(cl, g, tables, part, static_cast<int>(dirs.size()));
    parallel_for(last - first, [&](size_t a, size_t b, size_t) {
      std::vector<double> acc(3 * nc);
      for (size_t s = a; s < b; ++s) {
        std::fill(acc.begin(), acc.end(), 0.0);
        for (size_t k = 0; k < dirs.size(); ++k)
          for (int c = 0; c < 3; ++c) {
            float t = tau[(s * dirs.size() + k) * 3 + c];
            double f = p.sh_depth ? std::min(t, kDepthClamp) : std::exp(-double(t));
            for (int i = 0; i < nc; ++i) acc[c * nc + i] += f * basis[k * nc + i];
          }
        for (int i = 0; i < 3 * nc; ++i)
          bake.sh[(first + s) * 3 * nc + i] = static_cast<float>(acc[i] * w);
      }
    });
    report("sh", double(last) / n);
  }
  clock.stop("sh");
  return bake;
}

}  // namespace scatter
