#include "pipelines/reference/slab.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <numbers>

#include "../../test_util.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

constexpr double kPi = std::numbers::pi;

SlabResult slab(SlabParams p) {
  return run_reference_slab(test::shared_gpu().cl(), p);
}

double hg(double cos_t, double g) {
  double d = 1 + g * g - 2 * g * cos_t;
  return (1 - g * g) / (4 * kPi * d * std::sqrt(d));
}

// Gauss-Legendre-free midpoint quadrature over the exit hemisphere (mu in (0, 1], phi).
double hemisphere(const std::function<double(double mu, double phi)>& f) {
  const int nm = 400, np = 200;
  double s = 0;
  for (int i = 0; i < nm; ++i)
    for (int j = 0; j < np; ++j) s += f((i + 0.5) / nm, 2 * kPi * (j + 0.5) / np);
  return s / nm * (2 * kPi / np);
}

// Singly scattered reflectance and transmittance of a vacuum-bounded slab (sigma_t = 1), from
// the collision density exp(-z / mu0) / mu0, the phase function and the escape probability:
//   R1 = a Int_up   p mu / (mu + mu0) (1 - exp(-tau (1/mu + 1/mu0))) dw
//   T1 = a Int_down p mu / (mu - mu0) (exp(-tau / mu) - exp(-tau / mu0)) dw
void single_scattering(double tau, double a, double g, double mu0, double& R1, double& T1) {
  double s0 = std::sqrt(1 - mu0 * mu0);
  auto cos_theta = [&](double mu, double phi, bool up) {
    // Beam travels (s0, 0, mu0) with +z into the slab; "up" exits travel -z.
    double s = std::sqrt(1 - mu * mu);
    return s0 * s * std::cos(phi) + mu0 * (up ? -mu : mu);
  };
  R1 = a * hemisphere([&](double mu, double phi) {
         return hg(cos_theta(mu, phi, true), g) * mu / (mu + mu0) *
                (1 - std::exp(-tau * (1 / mu + 1 / mu0)));
       });
  T1 = a * hemisphere([&](double mu, double phi) {
         double k = std::abs(mu - mu0) < 1e-9
                        ? tau / mu0 * std::exp(-tau / mu0)
                        : mu / (mu - mu0) * (std::exp(-tau / mu) - std::exp(-tau / mu0));
         return hg(cos_theta(mu, phi, false), g) * k;
       });
}

// Standard error of the mean of a tally that is `a` with probability m / a, else 0.
double tally_se(double m, double a, double n) {
  return std::sqrt(std::max(0.0, a * m - m * m) / n);
}

// van de Hulst's table value as quoted for the MCML validation: tau 2, albedo 0.9, g 0.75,
// normal incidence, matched boundary: diffuse reflectance 0.09739, total transmittance 0.66096.
TEST(ReferenceSlab, MatchesPublishedTable) {
  SlabResult r =
      slab({.tau = 2, .albedo = 0.9, .g = 0.75, .mu0 = 1, .ior = 1, .photons = 2'000'000});
  EXPECT_NEAR(r.R_diffuse, 0.09739, 3 * r.R_stderr);
  EXPECT_NEAR(r.T, 0.66096, 3 * r.T_stderr);
  EXPECT_LT(r.R_stderr, 3e-4);
  EXPECT_EQ(r.R_specular, 0);
  EXPECT_NEAR(r.T_direct, std::exp(-2.0),
              4 * std::sqrt(std::exp(-2.0) * (1 - std::exp(-2.0)) / r.photons));
}

TEST(ReferenceSlab, SingleScatteringMatchesClosedForm) {
  for (double g : {0.0, 0.75})
    for (double mu0 : {1.0, 0.5}) {
      SCOPED_TRACE(testing::Message() << "g " << g << " mu0 " << mu0);
      const double tau = 1.5, a = 0.6;
      SlabResult r = slab({.tau = tau, .albedo = a, .g = g, .mu0 = mu0, .photons = 2'000'000});
      double R1, T1;
      single_scattering(tau, a, g, mu0, R1, T1);
      EXPECT_NEAR(r.R_single, R1, 4 * tally_se(R1, a, r.photons) + 1e-4 * R1);
      EXPECT_NEAR(r.T_single, T1, 4 * tally_se(T1, a, r.photons) + 1e-4 * T1);
    }
}

// Purely absorbing slab with index n: the unscattered beam bounces between the faces; with
// R0 the Fresnel reflectance at the refracted angle and x = exp(-tau / mu_t):
//   T = (1 - R0)^2 x / (1 - R0^2 x^2),  R = R0 + (1 - R0)^2 R0 x^2 / (1 - R0^2 x^2).
TEST(ReferenceSlab, AbsorbingSlabMatchesClosedForm) {
  for (double n : {1.0, 1.5})
    for (double mu0 : {1.0, 0.6}) {
      SCOPED_TRACE(testing::Message() << "n " << n << " mu0 " << mu0);
      const double tau = 0.7;
      SlabResult r = slab({.tau = tau, .albedo = 0, .mu0 = mu0, .ior = n, .photons = 1'000'000});
      double eta = 1 / n, st = eta * std::sqrt(1 - mu0 * mu0), mt = std::sqrt(1 - st * st);
      auto fresnel = [](double ci, double ct, double e) {
        double rs = (e * ci - ct) / (e * ci + ct), rp = (ci - e * ct) / (ci + e * ct);
        return 0.5 * (rs * rs + rp * rp);
      };
      double R0 = fresnel(mu0, mt, eta);  // the same at both faces and from either side
      double x = std::exp(-tau / mt), den = 1 - R0 * R0 * x * x;
      double T = (1 - R0) * (1 - R0) * x / den;
      double R = R0 + (1 - R0) * (1 - R0) * R0 * x * x / den;
      EXPECT_NEAR(r.T, T, 4 * r.T_stderr + 1e-6);
      EXPECT_NEAR(r.R, R, 4 * r.R_stderr + 1e-6);
      EXPECT_EQ(r.R_diffuse, 0);
      EXPECT_EQ(r.T_diffuse, 0);
    }
  // Normal incidence on n = 1.5: the front face reflects ((n - 1) / (n + 1))^2 = 0.04.
  SlabResult r = slab({.tau = 1e6, .albedo = 0, .mu0 = 1, .ior = 1.5, .photons = 1000});
  EXPECT_NEAR(r.R_specular, 0.04, 1e-6);
}

TEST(ReferenceSlab, ConservativeSlabsConserveEnergy) {
  for (double n : {1.0, 1.33})
    for (double g : {0.0, 0.9}) {
      SlabResult r =
          slab({.tau = 3, .albedo = 1, .g = g, .mu0 = 0.7, .ior = n, .photons = 200'000});
      EXPECT_NEAR(r.R + r.T, 1.0, 1e-4) << "n " << n << " g " << g;
    }
  // A half-space without absorption returns everything, but the time to return has a heavy tail:
  // the few photons still inside after the step bound are reported as lost, not hidden.
  SlabResult half = slab({.tau = INFINITY, .albedo = 1, .g = 0.5, .mu0 = 1, .photons = 20'000});
  EXPECT_NEAR(half.R + half.lost, 1.0, 1e-4);
  EXPECT_LT(half.lost, 0.02);
  EXPECT_EQ(half.T, 0);
}

// Chandrasekhar's H-function for isotropic scattering with albedo a, by fixed-point iteration of
// 1 / H(mu) = sqrt(1 - a) + (a / 2) Int_0^1 mu' H(mu') / (mu + mu') dmu' on a midpoint grid.
double chandrasekhar_h(double a, double mu) {
  const int n = 2000;
  std::vector<double> x(n), h(n, 1.0);
  for (int i = 0; i < n; ++i) x[i] = (i + 0.5) / n;
  auto eval = [&](double m) {
    double s = 0;
    for (int j = 0; j < n; ++j) s += x[j] * h[j] / (m + x[j]);
    return 1.0 / (std::sqrt(1 - a) + a / 2 * s / n);
  };
  for (int it = 0; it < 200; ++it) {
    std::vector<double> next(n);
    for (int i = 0; i < n; ++i) next[i] = eval(x[i]);
    h = next;
  }
  return eval(mu);
}

// A half-space of isotropic scatterers returns 1 - H(mu0) sqrt(1 - a) of a collimated beam
// (Chandrasekhar, Radiative Transfer, the plane albedo).
TEST(ReferenceSlab, HalfSpaceMatchesChandrasekhar) {
  for (double a : {0.5, 0.9, 0.99})
    for (double mu0 : {1.0, 0.4}) {
      SlabResult r = slab({.tau = INFINITY, .albedo = a, .g = 0, .mu0 = mu0, .photons = 400'000});
      double expected = 1 - chandrasekhar_h(a, mu0) * std::sqrt(1 - a);
      EXPECT_NEAR(r.R, expected, 4 * r.R_stderr + 1e-4) << "a " << a << " mu0 " << mu0;
      EXPECT_LT(r.lost, 1e-4);
    }
}

TEST(ReferenceSlab, RejectsBadParameters) {
  EXPECT_THROW(slab({.tau = -1}), ValidationError);
  EXPECT_THROW(slab({.albedo = 1.5}), ValidationError);
  EXPECT_THROW(slab({.g = 1}), ValidationError);
  EXPECT_THROW(slab({.mu0 = 0}), ValidationError);
  EXPECT_THROW(slab({.ior = 0.5}), ValidationError);
  EXPECT_THROW(slab({.photons = 10}), ValidationError);
}

}  // namespace
}  // namespace scatter
