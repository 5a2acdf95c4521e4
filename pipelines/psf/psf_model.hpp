// The point-spread-function model of multiple scattering (papers/psf-multiple-scattering.md), as
// plain functions: the kernels in kernels/psf/march.cl evaluate the same formulas, and the tests
// check these against the paper's limiting cases.
//
// Symbols (the paper's): a absorption, b scattering, c = a + b extinction coefficients; S the path
// length, l = integral of b along the path (the number of scattering events); <theta^2> the mean
// square scattering angle of the phase function; alpha = 1 / (4 (1 - g)).
#pragma once

#include <cstddef>
#include <vector>

namespace scatter::psf {

// Equation 2 for Henyey-Greenstein: 2 pi int_0^pi theta^2 P(theta) sin(theta) dtheta.
// g = 0 gives (pi^2 - 4) / 2; g = 0.9 gives about 0.24, the paper's figure 4 value.
double mean_square_angle(double g);

// The curvature constant of equation 11 as Algorithm 2 uses it.
double curvature_alpha(double g);

// Equation 18 (equation 1 with the 2/3 correction, reparameterised by l = b S):
//   w^2 = <theta^2> l S^2 / (24 (1 + <theta^2> (a/b) l^2 / 12)).
// The paper's 8/b shift: blurring starts after 8 scattering events, so l and S enter shifted,
// l' = max(l - shift, 0) and S' = S l' / l (the same fraction of the length). shift 0 is the bare
// formula. Returns w^2 (squared length).
double blur_width2(double theta2, double ell, double S, double a_over_b, double shift = 8.0);

// P_MS(l, theta) = P(theta / k) / N(l), k = sqrt(l / (1 - exp(-l))) (Tessendorf and Wasson),
// N(l) = int P(theta / k) d omega so that P_MS integrates to one over the sphere.
struct PmsTable {
  double g = 0;
  double log_min = 0, log_max = 0;       // ln(l) range covered; outside, the end values
  std::vector<float> inv_norm;           // 1 / N(l) at log-spaced l
  double inv_norm_at(double ell) const;  // linear in ln(l)
};
PmsTable pms_table(double g, int entries = 256, double ell_min = 1e-3, double ell_max = 1e4);
double pms_stretch(double ell);  // k(l)
// P_MS from the table (what the kernel does).
double pms(const PmsTable& table, double ell, double theta);
// N(l) by direct quadrature, independent of the table.
double pms_norm(double g, double ell, int steps = 4096);

// The pyramid's widths: level 0 is the source itself (width 0); level k >= 1 has voxels 2^k times
// the source's and, as the march reads it (trilinear), the total Gaussian width `level_width(k)` =
// kLevelWidth * 2^k source voxels. Trilinear reconstruction adds on average the variance of the
// tent of one voxel, 1/6 voxel^2 (kReconstruction), so the stored samples hold the source blurred
// by `stored_width(k)`, sqrt(level_width^2 - voxel^2 / 6). Level k is level k - 1 downsampled by 2
// with the tent [1 3 3 1] / 8 (variance 0.75 of the finer voxel^2), then blurred with a Gaussian
// of `level_sigma(k)` coarse voxels, so that the variances add up to stored_width(k)^2.
constexpr double kLevelWidth = 1.0;
constexpr double kReconstruction = 1.0 / 6.0;
double level_width(int level);   // in source voxels
double stored_width(int level);  // in source voxels
double level_sigma(int level);   // in voxels of `level`

// CPU versions of the pyramid's two operations on an nx * ny * nz grid of RGB (3 floats per voxel),
// for the tests: the tent downsample to ceil(n/2), and the separable Gaussian blur (zero outside),
// truncated at ceil(3 sigma) with weights summing to one.
struct Volume3 {
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> rgb;
  std::size_t index(int i, int j, int k) const { return (std::size_t(k) * ny + j) * nx + i; }
};
Volume3 downsample_tent(const Volume3& v);
Volume3 blur_gaussian(const Volume3& v, double sigma);
std::vector<float> gaussian_taps(double sigma);  // taps[0] is the centre, taps[i] = taps[-i]

// The `orders` model (model 1; docs/pipelines/psf.md): the light scattered m >= 1 times, order by
// order, as a random walk whose m-th flight after the first scattering (length exponential with
// mean 1 / c, direction HG-correlated with the previous one, the first with the light's) has
// moved the walk, on average, by g^m / c along the light and spread it by `variance` per axis.
// Both in mean free paths (multiply by 1 / c, squared for the variance). The variances add up to
// the walk's exact covariance (walk_mean_square - |mean|^2), so after many flights the spread
// grows as 2 m / (3 (1 - g)) per axis: diffusion with the reduced coefficient c (1 - g).
struct OrderFlight {
  double drift = 0;     // mean displacement along the light's direction
  double variance = 0;  // per-axis variance added by this flight
};
OrderFlight order_flight(double g, int m);  // m >= 1
// E|R_m|^2 of the walk after m flights, closed form (mean free paths squared):
//   2 m + 2 sum_{k=1}^{m-1} (m - k) g^k.
double walk_mean_square(double g, int m);
// Henyey-Greenstein composes as HG(g1) * HG(g2) = HG(g1 g2) (Legendre coefficients g^l), so light
// scattered m times, seen after one more scattering, has the phase HG(g^(m+1)) about the light's
// direction when its directions forget where it is.

}  // namespace scatter::psf
