#include "pipelines/lbl/slab.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/reference/slab.hpp"
#include "protocol/json_reader.hpp"

namespace scatter::lbl {
namespace {

LblSlabResult slab(double tau, double albedo, double g = 0, double mu0 = 1,
                   const LblSlabOptions& options = {}) {
  SlabParams p;
  p.tau = tau;
  p.albedo = albedo;
  p.g = g;
  p.mu0 = mu0;
  return run_lbl_slab(test::shared_gpu().cl(), p, options);
}

// Without absorption everything that enters leaves through one face or the other: at g 0 (where
// the pipeline's reading and the scaled problem's are the same), the whole slab read as the
// delta-Eddington scaled problem, and with the exact orders (their lattice's source is what the
// last order's light does not let out; measured within 0.3 % at mu0 0.8).
TEST(LblSlab, ConservativeSlabReflectsOrTransmitsEverything) {
  for (double tau : {1.0, 8.0}) {
    for (double g : {0.0, 0.75}) {
      LblSlabResult r = slab(tau, 1.0, g, 0.8, {.scaled_view = g != 0});
      EXPECT_TRUE(r.converged);
      EXPECT_NEAR(r.R + r.T, 1.0, 1e-3) << "tau " << tau << " g " << g;
      EXPECT_NEAR(r.T_direct, std::exp(-tau / 0.8), 1e-12);
      LblSlabResult orders = slab(tau, 1.0, g, 0.8, {.orders = 4});
      EXPECT_NEAR(orders.R + orders.T, 1.0, 0.01) << "tau " << tau << " g " << g;
      ASSERT_EQ(orders.orders.size(), 3u);
      for (const SingleScattering& o : orders.orders) EXPECT_GT(o.R + o.T, 0);
    }
  }
}

// The pipeline's reading at g 0.75 (scaled_view 0, the default) is not the scaled problem's: the
// real single term and the forward-scattered light's scattering by the HG phase take the place
// of the scaled problem's isotropic single scattering and its beam's exit.
TEST(LblSlab, PipelineReadingKeepsTheRealSingleTerm) {
  LblSlabResult pipeline = slab(4, 0.99, 0.75, 0.1),
                scaled = slab(4, 0.99, 0.75, 0.1, {.scaled_view = true});
  SlabParams p;
  p.tau = 4;
  p.albedo = 0.99;
  p.g = 0.75;
  p.mu0 = 0.1;
  SingleScattering real = slab_single_scattering(p);
  EXPECT_DOUBLE_EQ(pipeline.R_single, real.R);
  EXPECT_NE(scaled.R_single, real.R);
  EXPECT_GT(pipeline.R_forward, 0);
  EXPECT_EQ(scaled.R_forward, 0);
  // At g 0 the two readings are the same.
  EXPECT_DOUBLE_EQ(slab(4, 0.9, 0, 0.1).R, slab(4, 0.9, 0, 0.1, {.scaled_view = true}).R);
}

// With the real medium's orders 2 to 8 computed exactly, the lattice carrying only the ninth and
// later events, the slab is within 3 % of the reference's transport at g 0.75 and at grazing
// incidence, where the pipeline's own reading is 10-60 % off (docs/BENCHMARKS.md): what is off
// there is the lattice's delta-isotropic tail, not the view's quadrature. Stored references:
// `scatterd slab --solver reference --photons 400000` (standard errors under 0.0007).
TEST(LblSlab, ExactOrdersBringTheSlabToTheReference) {
  struct Case {
    double tau, albedo, g, mu0, R, T;
  };
  for (Case c :
       {Case{4, 0.99, 0.75, 1, 0.28502, 0.64566}, Case{4, 0.99, 0.75, 0.1, 0.69917, 0.24118},
        Case{4, 0.9, 0, 0.1, 0.62739, 0.04171}}) {
    LblSlabResult r = slab(c.tau, c.albedo, c.g, c.mu0, {.orders = 8});
    EXPECT_NEAR(r.R, c.R, 0.03 * c.R) << "g " << c.g << " mu0 " << c.mu0;
    EXPECT_NEAR(r.T, c.T, 0.03 * c.T) << "g " << c.g << " mu0 " << c.mu0;
    LblSlabResult pipeline = slab(c.tau, c.albedo, c.g, c.mu0);
    EXPECT_LT(std::abs(r.T - c.T), std::abs(pipeline.T - c.T)) << "g " << c.g << " mu0 " << c.mu0;
  }
  SlabParams p;
  EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p, {.orders = 1}), ValidationError);
  p.tau = 200;
  EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p, {.orders = 2}), ValidationError);
}

TEST(LblSlab, AbsorbingSlabWithoutScatteringOnlyTransmitsTheBeam) {
  LblSlabResult r = slab(2, 0);
  EXPECT_EQ(r.R, 0);
  EXPECT_EQ(r.T_diffuse, 0);
  EXPECT_NEAR(r.absorbed, 1 - std::exp(-2.0), 1e-12);
}

// More scattering reflects more; a thicker slab transmits less; forward scattering reflects less.
TEST(LblSlab, TrendsFollowTransport) {
  LblSlabResult low = slab(4, 0.5), high = slab(4, 0.99);
  EXPECT_LT(low.R, high.R);
  EXPECT_GT(slab(2, 0.9).T, slab(8, 0.9).T);
  EXPECT_LT(slab(4, 0.9, 0.75).R, slab(4, 0.9, 0.0).R);
  EXPECT_GT(high.absorbed, 0);
}

// The single scattering by quadrature against the reference's Monte Carlo count of photons
// leaving after one scattering, at normal and grazing incidence, isotropic and forward phase.
TEST(LblSlab, SingleScatteringMatchesTheReference) {
  for (auto [tau, albedo, g, mu0] : {std::array{4.0, 0.9, 0.0, 0.1},
                                     {2.0, 0.99, 0.75, 0.1},
                                     {1.0, 0.9, 0.75, 1.0},
                                     {4.0, 0.9, 0.0, 1.0}}) {
    SlabParams p;
    p.tau = tau;
    p.albedo = albedo;
    p.g = g;
    p.mu0 = mu0;
    p.photons = 200000;
    SlabResult ref = run_reference_slab(test::shared_gpu().cl(), p);
    SingleScattering s = slab_single_scattering(p);
    // The Monte Carlo counts' standard errors: sqrt(x (1 - x) / photons) <= 0.0012.
    EXPECT_NEAR(s.R, ref.R_single, 0.005) << "tau " << tau << " g " << g << " mu0 " << mu0;
    EXPECT_NEAR(s.T, ref.T_single, 0.005) << "tau " << tau << " g " << g << " mu0 " << mu0;
  }
}

// Against the reference's transport (stored: `scatterd slab --solver reference --photons 400000`,
// standard errors under 0.0008; docs/BENCHMARKS.md, lbl, issue 16). With the orders 2 to 4
// gathered exactly (the defaults: second, gathers 3), at g 0 R and T within 5 % at normal and
// grazing incidence (measured R -0.4 to +1.6 %, T -0.2 to -4.1 %, grazing T -4.1 %). The second
// alone (gathers 1) measured T -2.0 to -5.7 %, grazing -16.7 % (the 6 directions carrying the
// third and later events); the lattice from the first scattering (second 0) R +3.4 to +4.4 %,
// T -4.4 to -8.9 %, grazing R +10.7 %, T -36 %.
LblSlabResult slab_from(bool second, double tau, double albedo, double mu0, int gathers = 3) {
  SlabParams p;
  p.tau = tau;
  p.albedo = albedo;
  p.mu0 = mu0;
  return run_lbl_slab(test::shared_gpu().cl(), p, {.second = second, .gathers = gathers});
}

TEST(LblSlab, ReflectanceIsNearTheReference) {
  struct Case {
    double tau, albedo, mu0, R, T;
  };
  for (Case c : {Case{2, 0.9, 1, 0.36172, 0.35606}, Case{4, 0.99, 1, 0.64521, 0.27529},
                 Case{8, 0.9, 1, 0.41494, 0.015883}}) {
    LblSlabResult r = slab(c.tau, c.albedo, 0, c.mu0);
    EXPECT_NEAR(r.R, c.R, 0.05 * c.R) << "tau " << c.tau << " albedo " << c.albedo;
    EXPECT_NEAR(r.T, c.T, 0.05 * c.T) << "tau " << c.tau << " albedo " << c.albedo;
    LblSlabResult first = slab_from(false, c.tau, c.albedo, c.mu0);
    EXPECT_LT(std::abs(r.T - c.T), std::abs(first.T - c.T)) << "tau " << c.tau;
  }
  const double R = 0.62739, T = 0.041707;  // tau 4, albedo 0.9, mu0 0.1
  LblSlabResult grazing = slab(4, 0.9, 0, 0.1), first = slab_from(false, 4, 0.9, 0.1),
                one = slab_from(true, 4, 0.9, 0.1, 1);
  EXPECT_NEAR(grazing.R, R, 0.05 * R);
  EXPECT_NEAR(grazing.T, T, 0.05 * T);
  EXPECT_NEAR(one.T, T, 0.20 * T);
  EXPECT_NEAR(first.T, T, 0.40 * T);  // the lattice alone keeps the light at the lit face
  EXPECT_LT(std::abs(grazing.T - T), 0.5 * std::abs(one.T - T));
  EXPECT_LT(std::abs(one.T - T), 0.5 * std::abs(first.T - T));
  // The slab's default is the pipeline's.
  EXPECT_EQ(LblSlabOptions{}.gathers, LblSettings{}.gathers);
  SlabParams p;
  p.tau = 4;
  p.albedo = 0.9;
  for (int bad : {0, kMaxGathers + 1})
    EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p, {.gathers = bad}), ValidationError);
}

TEST(LblSlab, RejectsWhatTheLatticeDoesNotModel) {
  SlabParams p;
  p.tau = INFINITY;
  EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p), ValidationError);
  p.tau = 1;
  p.ior = 1.33;
  EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p), ValidationError);
  p.ior = 1;
  p.albedo = 1.5;
  EXPECT_THROW(run_lbl_slab(test::shared_gpu().cl(), p), ValidationError);
}

}  // namespace
}  // namespace scatter::lbl
