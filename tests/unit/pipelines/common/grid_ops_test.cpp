#include "pipelines/common/grid_ops.hpp"

#include <gtest/gtest.h>

#include <random>

#include "../../test_util.hpp"

namespace scatter {
namespace {

// The brick-majorant kernel against the same computation on the CPU.
TEST(GridOps, BrickMajorantsMatchTheCpu) {
  VoxelGrid g;
  g.nx = 19;
  g.ny = 13;
  g.nz = 10;  // not multiples of the brick, so partial bricks are covered
  g.sigma_s.resize(3 * g.count());
  g.sigma_a.resize(3 * g.count());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  for (size_t i = 0; i < g.sigma_s.size(); ++i) {
    g.sigma_s[i] = u(rng) < 0.7 ? 0.f : 10 * u(rng);
    g.sigma_a[i] = u(rng);
  }
  const int b = 4;
  BrickGrid gpu_result = brick_majorants(test::shared_gpu().cl(), g, b);
  ASSERT_EQ(gpu_result.bx, 5);
  ASSERT_EQ(gpu_result.bz, 3);
  for (int bk = 0; bk < gpu_result.bz; ++bk)
    for (int bj = 0; bj < gpu_result.by; ++bj)
      for (int bi = 0; bi < gpu_result.bx; ++bi) {
        float m = 0;
        for (int k = std::max(bk * b - 1, 0); k < std::min(bk * b + b + 1, g.nz); ++k)
          for (int j = std::max(bj * b - 1, 0); j < std::min(bj * b + b + 1, g.ny); ++j)
            for (int i = std::max(bi * b - 1, 0); i < std::min(bi * b + b + 1, g.nx); ++i)
              for (int c = 0; c < 3; ++c) {
                size_t v = 3 * g.index(i, j, k) + c;
                m = std::max(m, g.sigma_s[v] + g.sigma_a[v]);
              }
        EXPECT_EQ(gpu_result.majorant[(size_t(bk) * gpu_result.by + bj) * gpu_result.bx + bi], m);
      }
}

}  // namespace
}  // namespace scatter
