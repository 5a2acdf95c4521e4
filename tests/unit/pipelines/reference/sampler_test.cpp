// The path tracer's stratified sampler (kernels/common/rng.cl: padded, Owen-scrambled Sobol): the
// kernel's draws against the same computation on the CPU, each batch a (0, m, 2)-net, and the
// draws uniform and independent across dimensions, pixels and batches.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "../../test_util.hpp"
#include "pipelines/common/cl_library.hpp"

namespace scatter {
namespace {

// ---- The sampler on the CPU, line for line as rng.cl --------------------------------------------

uint32_t reverse_bits32(uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
  return (x >> 16) | (x << 16);
}

uint32_t laine_karras(uint32_t x, uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

uint32_t owen_scramble(uint32_t x, uint32_t seed) {
  return reverse_bits32(laine_karras(reverse_bits32(x), seed));
}

uint32_t sobol_dim1(uint32_t i) {
  uint32_t r = 0;
  for (uint32_t v = 1u << 31; i != 0; i >>= 1, v ^= v >> 1)
    if (i & 1u) r ^= v;
  return r;
}

uint32_t mix32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

float unit_fraction(uint32_t x) {
  return float(x >> 8) * (1.0f / 16777216.0f);
}

// A sample's first draws: a 1D, then a 2D (kernels/reference/sampler_draws.cl).
std::array<float, 3> cpu_draws(uint32_t pixel, uint32_t index, uint32_t batch_seed) {
  std::array<float, 3> out{};
  for (uint32_t dim = 0; dim < 2; ++dim) {
    uint32_t h = mix32(pixel ^ mix32(dim * 0x9E3779B9u ^ mix32(batch_seed)));
    uint32_t i = owen_scramble(index, h);
    float x = unit_fraction(owen_scramble(reverse_bits32(i), mix32(h ^ 0xa511e9b3u)));
    if (dim == 0) {
      out[0] = x;
    } else {
      out[1] = x;
      out[2] = unit_fraction(owen_scramble(sobol_dim1(i), mix32(h ^ 0x63d83595u)));
    }
  }
  return out;
}

// ---- The kernel's draws ----------------------------------------------------------------------

struct Draws {
  int count, batches, pixels;
  std::vector<float> v;  // 3 per (pixel, batch, index)
  const float* at(int pixel, int batch, int index) const {
    return &v[3 * ((size_t(pixel) * batches + batch) * count + index)];
  }
};

Draws gpu_draws(int count, int batches, int pixels, uint32_t seed) {
  gpu::ClContext& cl = test::shared_gpu().cl();
  Draws d{count, batches, pixels, std::vector<float>(3 * size_t(count) * batches * pixels)};
  cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, d.v.size() * sizeof(float));
  cl::Kernel k(cl.program(with_cl_library({"kernels/reference/sampler_draws.cl"})),
               "sampler_draws");
  gpu::set_args(k, count, batches, seed, out);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(count, batches, pixels));
  cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, d.v.size() * sizeof(float), d.v.data());
  return d;
}

TEST(Sampler, KernelMatchesItsCpuComputation) {
  const uint32_t seed = 7;
  Draws d = gpu_draws(16, 8, 5, seed);
  for (int p = 0; p < d.pixels; ++p)
    for (int b = 0; b < d.batches; ++b)
      for (int i = 0; i < d.count; ++i) {
        auto want = cpu_draws(p, i, mix32(seed ^ mix32(b)));
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(d.at(p, b, i)[c], want[c]) << "pixel " << p << " batch " << b << " index " << i;
      }
}

// In every batch the first 2^m samples (m <= 4 of 16) hold one 1D draw in each interval
// [k, k + 1) / 2^m and one 2D draw in each elementary box 2^-a x 2^-(m - a): a (0, m, 2)-net.
TEST(Sampler, EveryBatchAndItsPowerOfTwoPrefixesAreNets) {
  Draws d = gpu_draws(16, 64, 3, 11);
  for (int p = 0; p < d.pixels; ++p)
    for (int b = 0; b < d.batches; ++b)
      for (int m = 1; m <= 4; ++m) {
        const int n = 1 << m;
        std::vector<int> strata(n, 0);
        for (int i = 0; i < n; ++i) ++strata[int(d.at(p, b, i)[0] * n)];
        for (int k = 0; k < n; ++k) ASSERT_EQ(strata[k], 1) << "1D, " << n << " samples";
        for (int a = 0; a <= m; ++a) {
          const int nx = 1 << a, ny = 1 << (m - a);
          std::vector<int> boxes(n, 0);
          for (int i = 0; i < n; ++i) {
            const float* v = d.at(p, b, i);
            ++boxes[int(v[1] * nx) * ny + int(v[2] * ny)];
          }
          for (int k = 0; k < n; ++k)
            ASSERT_EQ(boxes[k], 1) << "2D, " << nx << " x " << ny << " boxes";
        }
      }
}

// Each draw is uniform (counts in 256 bins within 5 sigma of binomial), and draws of other
// dimensions, other pixels and other batches are uncorrelated (|r| under 5 / sqrt(n)).
TEST(Sampler, DrawsAreUniformAndIndependent) {
  Draws d = gpu_draws(16, 2048, 2, 3);
  const int n = d.count * d.batches;
  for (int c = 0; c < 3; ++c) {
    std::vector<int> bins(256, 0);
    for (int b = 0; b < d.batches; ++b)
      for (int i = 0; i < d.count; ++i) ++bins[int(d.at(0, b, i)[c] * 256)];
    const double expect = n / 256.0, sd = std::sqrt(expect * (1 - 1 / 256.0));
    for (int k = 0; k < 256; ++k) ASSERT_NEAR(bins[k], expect, 5 * sd) << "draw " << c;
  }
  auto correlation = [&](auto x, auto y) {
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (int b = 0; b < d.batches; ++b)
      for (int i = 0; i < d.count; ++i) {
        double a = x(b, i), e = y(b, i);
        sx += a, sy += e, sxx += a * a, syy += e * e, sxy += a * e;
      }
    double cov = sxy / n - sx * sy / n / n;
    return cov / std::sqrt((sxx / n - sx * sx / n / n) * (syy / n - sy * sy / n / n));
  };
  const double bound = 5 / std::sqrt(double(n));
  // The 1D draw against the 2D's first coordinate (the same Sobol dimension, other shuffles).
  EXPECT_LT(std::abs(correlation([&](int b, int i) { return d.at(0, b, i)[0]; },
                                 [&](int b, int i) { return d.at(0, b, i)[1]; })),
            bound);
  // Two pixels' same samples.
  EXPECT_LT(std::abs(correlation([&](int b, int i) { return d.at(0, b, i)[0]; },
                                 [&](int b, int i) { return d.at(1, b, i)[0]; })),
            bound);
  // Neighbouring batches' same indices.
  EXPECT_LT(std::abs(correlation([&](int b, int i) { return d.at(0, b, i)[0]; },
                                 [&](int b, int i) { return d.at(0, (b + 1) % 2048, i)[0]; })),
            bound);
}

}  // namespace
}  // namespace scatter
