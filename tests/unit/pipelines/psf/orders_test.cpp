// The `orders` model's kernels (kernels/psf/orders.cl) against a CPU computation of the same
// steps: the plain orders (b capped) and the conserving ones (the default).
#include "pipelines/psf/orders.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../../test_util.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/psf/light_pyramid.hpp"
#include "pipelines/psf/psf_model.hpp"
#include "psf_volumes.hpp"
#include "scene/scene.hpp"

namespace scatter::psf {
namespace {

using test_volumes::random_volume;
using test_volumes::upload4;

// A cube of n^3 voxels of 0.1 with scattering `b` at albedo 0.9, lit by the sun, and the
// pyramid over `src`.
struct Case {
  ClMedium m;
  std::vector<float> t;  // sigma_t
  cl::Buffer lights;
  Pyramid p;
  Case(gpu::ClContext& cl, const Volume3& src, const Volume3& b) : t(b.rgb) {
    m.nx = b.nx, m.ny = b.ny, m.nz = b.nz;
    m.voxel = 0.1f;
    m.origin = cl_float3{{-1, -1, -1}};
    m.sigma_s = upload(cl, b.rgb);
    for (float& x : t) x /= 0.9f;
    m.sigma_t = upload(cl, t);
    Light sun;
    sun.type = Light::Type::Directional;
    lights = upload(cl, pack_lights({sun}));
    p = build_pyramid(cl, upload4(cl, src), b.nx, b.ny, b.nz, m.voxel);
  }
};

// The largest relative difference between the bands (orders 1, 2, the rest and the rest's phase
// moment) and the CPU's.
double worst_band(const Orders& o, gpu::ClContext& cl, const std::vector<Volume3>& cpu) {
  const size_t voxels = size_t(o.nx) * o.ny * o.nz;
  std::vector<cl_float4> bands(voxels * 4);
  cl.queue().enqueueReadBuffer(o.bands, CL_TRUE, 0, bands.size() * sizeof(cl_float4), bands.data());
  double worst = 0;
  for (size_t v = 0; v < voxels; ++v)
    for (size_t j = 0; j < cpu.size(); ++j)
      for (int c = 0; c < 3; ++c) {
        const double want = cpu[j].rgb[3 * v + c];
        worst = std::max(worst, std::fabs(bands[4 * v + j].s[c] - want) / (std::fabs(want) + 1e-3));
      }
  return worst;
}

// g 0 (no drift), level 0, one Gaussian per flight, c per channel, `orders` orders and no tail.
OrderParams level0_params(int orders) {
  return {.g = 0,
          .mean_sigma_t = {2.0, 2.5, 3.0},
          .level = 0,
          .tolerance = 0,
          .max_orders = orders,
          .flights = 1,
          .tail = false};
}

TEST(PsfOrders, KernelsMatchTheCpuOrders) {
  // g = 0 (no drift), level 0, one Gaussian per flight: order m's fluence is the source blurred by
  // its flight's Gaussian (per channel: c differs) over c, and the next source is b times it.
  auto& cl = test::shared_gpu().cl();
  const int n = 20;
  Volume3 src = random_volume(n, n, n, 5), b = random_volume(n, n, n, 9);
  Case k(cl, src, b);  // albedo 0.9: b stays below 0.9 c_mean, uncapped
  OrderParams params = level0_params(5);
  params.conserve = false;
  Orders o = build_orders(cl, k.m, cl::Buffer(), k.p, k.lights, 0, params);
  ASSERT_EQ(o.count, 5);
  ASSERT_EQ(o.nx, n);
  Volume3 q = src;
  std::vector<Volume3> cpu(4, Volume3{n, n, n, std::vector<float>(src.rgb.size(), 0.f)});
  for (int order = 1; order <= 5; ++order) {
    Volume3 phi = q;
    for (int c = 0; c < 3; ++c) {
      const double st = params.mean_sigma_t[c];
      Volume3 blurred =
          blur_gaussian(q, std::sqrt(order_flight(0, order).variance) / st / k.m.voxel);
      for (size_t i = c; i < phi.rgb.size(); i += 3)
        phi.rgb[i] = static_cast<float>(blurred.rgb[i] / st);
    }
    Volume3& band = cpu[std::min(order - 1, 2)];
    for (size_t i = 0; i < phi.rgb.size(); ++i) {
      band.rgb[i] += phi.rgb[i];
      q.rgb[i] = b.rgb[i] * phi.rgb[i];
    }
  }
  EXPECT_LT(worst_band(o, cl, cpu), 1e-4);  // and the phase moment zero: g^(m+1) = 0
}

// `conserve`: each order's source is scaled by E c_mean / N (N = the flight's blur of c_eff, E of
// the occupancy), the fluence is the scaled source's flight over c_mean and the next source is
// b_eff times it, with c_eff = (1 - e^(-c dl)) / dl and b_eff = c_eff b / c at dl = the voxel
// (level 0). On a layered medium (b 10x in every other slab of 4 voxels) with a partial
// occupancy, against the same steps on the CPU; and no order gains power.
TEST(PsfOrders, ConservingKernelsMatchTheCpuOrders) {
  auto& cl = test::shared_gpu().cl();
  const int n = 16;
  Volume3 src = random_volume(n, n, n, 5), b = random_volume(n, n, n, 9);
  std::vector<float> occ(size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const size_t v = b.index(i, j, k);
        const bool inside = i >= 2 && i < n - 2 && k >= 1 && k < n - 1;
        occ[v] = inside ? (i == 2 ? 0.5f : 1.f) : 0.f;
        for (int c = 0; c < 3; ++c) b.rgb[3 * v + c] *= occ[v] * ((j / 4) % 2 ? 10.f : 1.f);
      }
  Case k(cl, src, b);
  OrderParams params = level0_params(4);
  ASSERT_TRUE(params.conserve);  // the default
  Orders o = build_orders(cl, k.m, upload(cl, occ), k.p, k.lights, 0, params);
  ASSERT_EQ(o.count, 4);
  EXPECT_EQ(o.normalisations, 1);  // g 0: every flight the same
  // The CPU's coefficients and the flight's blur per channel (g 0: the same for every order).
  const double dl = k.m.voxel;
  Volume3 ceff = b, beff = b, occ3 = b;
  for (size_t i = 0; i < b.rgb.size(); ++i) {
    const double ce = k.t[i] > 0 ? -std::expm1(-k.t[i] * dl) / dl : 0.0;
    ceff.rgb[i] = static_cast<float>(ce);
    beff.rgb[i] = static_cast<float>(k.t[i] > 0 ? ce * b.rgb[i] / k.t[i] : 0.0);
    occ3.rgb[i] = occ[i / 3];
  }
  auto flight = [&](const Volume3& v, int c) {
    const double st = params.mean_sigma_t[c];
    return blur_gaussian(v, std::sqrt(order_flight(0, 1).variance) / st / k.m.voxel);
  };
  Volume3 scale = b;
  for (int c = 0; c < 3; ++c) {
    Volume3 nb = flight(ceff, c), eb = flight(occ3, c);
    const double st = params.mean_sigma_t[c];
    for (size_t i = c; i < scale.rgb.size(); i += 3)
      scale.rgb[i] = nb.rgb[i] > 1e-6 * st ? static_cast<float>(eb.rgb[i] * st / nb.rgb[i]) : 0.f;
  }
  Volume3 q = src;
  std::vector<Volume3> cpu(4, Volume3{n, n, n, std::vector<float>(src.rgb.size(), 0.f)});
  double power = 0;
  for (float x : q.rgb) power += x;
  for (int order = 1; order <= 4; ++order) {
    for (size_t i = 0; i < q.rgb.size(); ++i) q.rgb[i] *= scale.rgb[i];
    double collided = 0, scattered = 0;
    for (int c = 0; c < 3; ++c) {
      Volume3 blurred = flight(q, c);
      for (size_t i = c; i < q.rgb.size(); i += 3) {
        const double phi = blurred.rgb[i] / params.mean_sigma_t[c];
        cpu[std::min(order - 1, 2)].rgb[i] += static_cast<float>(phi);
        collided += ceff.rgb[i] * phi;
        q.rgb[i] = static_cast<float>(beff.rgb[i] * phi);
        scattered += q.rgb[i];
      }
    }
    EXPECT_LE(collided, power * 1.0001) << order;         // what stays inside, at most all
    EXPECT_LE(scattered, 0.9 * power * 1.0001) << order;  // and the albedo's share of it
    power = scattered;
  }
  EXPECT_LT(worst_band(o, cl, cpu), 1e-4);
}

}  // namespace
}  // namespace scatter::psf
