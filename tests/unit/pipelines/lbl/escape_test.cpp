#include "pipelines/lbl/escape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../../test_util.hpp"

namespace scatter::lbl {
namespace {

// A 16^3 grid of voxels 0.1 wide (the box [-0.8, 0.8]^3) filled with one medium.
Volume filled(float sigma_s, float sigma_t) {
  Volume v;
  v.nx = v.ny = v.nz = 16;
  v.voxel = 0.1;
  v.origin = {-0.8, -0.8, -0.8};
  v.sigma_s.assign(3 * v.count(), sigma_s);
  v.sigma_t.assign(3 * v.count(), sigma_t);
  return v;
}

// The kernel against the same mean over the same 64 Fibonacci directions on the CPU: in a
// homogeneous box the optical depth to the edge is sigma_t' times the distance to the box, the
// part inside the own voxel weighted by exp(-sigma_t' dx).
TEST(LblEscape, ExactEscapeMatchesACpuComputation) {
  const float ss = 2, st = 2.5;
  const double g = 0.5;
  Volume v = filled(ss, st);
  std::vector<float> p = exact_escape(test::shared_gpu().cl(), v, g, 64);
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0)), sts = st - g * ss;
  for (int i : {0, 3, 8, 15}) {
    Vec3 o = v.origin + Vec3{i + 0.5, 8.5, 7.5} * v.voxel;
    double mean = 0;
    for (int k = 0; k < 64; ++k) {
      double z = 1 - (k + 0.5) * 2 / 64, r = std::sqrt(1 - z * z);
      Vec3 d{r * std::cos(golden * k), r * std::sin(golden * k), z};
      double t = 1e30, own = 1e30;  // to the box's face, and to the own voxel's
      for (int a = 0; a < 3; ++a)
        if (std::abs(d[a]) > 1e-12) {
          t = std::min(t, ((d[a] > 0 ? 0.8 : -0.8) - o[a]) / d[a]);
          own = std::min(own, 0.5 * v.voxel / std::abs(d[a]));
        }
      mean += std::exp(-sts * (t - own) - sts * std::exp(-sts * v.voxel) * own) / 64;
    }
    EXPECT_NEAR(p[3 * v.index(i, 8, 7)], mean, 1e-4 + 1e-3 * mean) << "i " << i;
  }
}

TEST(LblEscape, LatticeEscapeIsASixthOfTheAxisTransmittances) {
  Volume v = filled(1, 1);
  LatticeCoefficients c = lattice_coefficients(v, 0);
  std::vector<float> p = lattice_escape(c);
  const double keep = 1 - c.pt[0];
  for (auto [i, j, k] : {std::array{0, 0, 0}, {3, 8, 12}, {15, 7, 1}}) {
    double expected = 0;
    for (int x : {i, j, k}) expected += (std::pow(keep, x) + std::pow(keep, 15 - x)) / 6;
    EXPECT_NEAR(p[3 * v.index(i, j, k)], expected, 1e-5) << i << " " << j << " " << k;
  }
}

TEST(LblEscape, FactorKeepsWhatWouldInteractAgain) {
  std::vector<float> m = escape_factor({0.5f, 0.f, 0.3f, 0.2f}, {1 / 6.f, 0.05f, 1.f, 0.4f});
  EXPECT_NEAR(m[0], 0.5 / (5 / 6.0), 1e-6);  // a node on a flat face: 0.6 carried on
  EXPECT_NEAR(m[1], 1 / 0.95, 1e-6);         // deep: the lattice's axis escape gives some back
  EXPECT_EQ(m[2], 1.f);                      // nothing stays in the lattice: left as it is
  EXPECT_NEAR(m[3], 0.8 / 0.6, 1e-6);        // and m (1 - P_lattice) = 1 - P in general
}

}  // namespace
}  // namespace scatter::lbl
