#include "pipelines/lbl/lattice.hpp"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <functional>
#include <random>

#include "../../test_util.hpp"

namespace scatter::lbl {
namespace {

gpu::ClContext& cl() {
  return test::shared_gpu().cl();
}

// Coefficients for an n^3 grid; `scatter(i, j, k)` gives (pt, ps) per node, the same for all
// channels; w = ps.
LatticeCoefficients coefficients(int n,
                                 const std::function<std::pair<float, float>(int, int, int)>& f) {
  LatticeCoefficients c;
  c.nx = c.ny = c.nz = n;
  size_t count = size_t(n) * n * n;
  c.pt.resize(3 * count);
  c.ps.resize(3 * count);
  c.w.resize(3 * count);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        auto [pt, ps] = f(i, j, k);
        size_t node = (size_t(k) * n + j) * n + i;
        for (int ch = 0; ch < 3; ++ch) {
          c.pt[3 * node + ch] = pt;
          c.ps[3 * node + ch] = ps;
          c.w[3 * node + ch] = ps;
        }
      }
  c.pt_diag = c.pt;
  c.ps_diag = c.ps;
  c.w_diag = c.w;
  return c;
}

std::vector<float> random_state(size_t nodes, unsigned seed, int directions = 6) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<float> f(3 * directions * nodes);
  for (float& x : f) x = u(rng);
  return f;
}

LatticeOptions closed(bool blocked, int inner = 1) {
  return {.blocked = blocked,
          .block = 4,
          .inner = inner,
          .edges = {Edge::Reflect, Edge::Reflect, Edge::Reflect}};
}

// What arrives at node (i, j, k) along each direction d, a_d = f_d(r - c_d), or at an edge what
// comes in there.
void cpu_arrivals(const LatticeCoefficients& c, const std::array<Edge, 3>& edges,
                  const std::vector<double>& f, int i, int j, int k, double a[6][3]) {
  const int dims[3] = {c.nx, c.ny, c.nz};
  const size_t n = size_t(c.nx) * c.ny * c.nz, node = (size_t(k) * c.ny + j) * c.nx + i;
  for (int d = 0; d < 6; ++d) {
    int s[3] = {i, j, k};
    int axis = d / 2;
    s[axis] -= (d & 1) ? -1 : 1;
    bool outside = s[axis] < 0 || s[axis] >= dims[axis];
    if (outside && edges[axis] == Edge::Periodic) {
      s[axis] = (s[axis] + dims[axis]) % dims[axis];
      outside = false;
    }
    size_t sn = (size_t(s[2]) * c.ny + s[1]) * c.nx + s[0];
    for (int ch = 0; ch < 3; ++ch)
      a[d][ch] = !outside ? f[(d * 3 + ch) * n + sn]
                          : (edges[axis] == Edge::Reflect ? f[((d ^ 1) * 3 + ch) * n + node] : 0.0);
  }
}

// The global step on the CPU, in double: f_d(r) = (1 - pt) a_d + ps/6 sum a + src/6.
void cpu_step(const LatticeCoefficients& c, const std::vector<float>& src,
              const std::array<Edge, 3>& edges, std::vector<double>& f, std::vector<double>& irr) {
  const size_t n = size_t(c.nx) * c.ny * c.nz;
  std::vector<double> out(f.size());
  irr.assign(3 * n, 0);
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        size_t node = (size_t(k) * c.ny + j) * c.nx + i;
        double a[6][3];
        cpu_arrivals(c, edges, f, i, j, k, a);
        for (int ch = 0; ch < 3; ++ch) {
          double sum = 0;
          for (int d = 0; d < 6; ++d) sum += a[d][ch];
          double pt = c.pt[3 * node + ch], ps = c.ps[3 * node + ch];
          for (int d = 0; d < 6; ++d)
            out[(d * 3 + ch) * n + node] =
                (1 - pt) * a[d][ch] + (ps * sum + src[3 * node + ch]) / 6;
          irr[3 * node + ch] = c.w[3 * node + ch] * sum;
        }
      }
  f = std::move(out);
}

TEST(LblLattice, ConservesEnergyWithoutAbsorptionInAClosedBox) {
  // Heterogeneous collision chances, no absorption (ps = pt).
  auto c = coefficients(8, [](int i, int j, int k) {
    float pt = 0.05f + 0.9f * ((i * 7 + j * 3 + k * 5) % 11) / 10.f;
    return std::pair{pt, pt};
  });
  for (bool blocked : {false, true}) {
    SCOPED_TRACE(blocked ? "blocked" : "global");
    Lattice l(cl(), c, closed(blocked));
    l.set_state(random_state(l.nodes(), 3));
    double e0 = l.energy();
    // Only float rounding may move the total: at most about one FLT_EPSILON per step.
    for (int round = 1; round <= 4; ++round) {
      l.step(50);
      EXPECT_NEAR(l.energy(), e0, 50 * round * FLT_EPSILON * e0);
    }
  }
}

TEST(LblLattice, AbsorptionRemovesTheExpectedFractionEachStep) {
  // Homogeneous: every packet collides with the same chances, so each step keeps 1 - pt + ps.
  const float pt = 0.3f, ps = 0.24f;
  auto c = coefficients(8, [&](int, int, int) { return std::pair{pt, ps}; });
  Lattice l(cl(), c, closed(true));
  l.set_state(random_state(l.nodes(), 5));
  double e = l.energy(), e0 = e;
  for (int step = 1; step <= 20; ++step) {
    l.step(1);
    double now = l.energy();
    EXPECT_LT(now, e);
    EXPECT_NEAR(now, e0 * std::pow(1.0 - pt + ps, step), 1e-5 * e0);
    e = now;
  }
}

TEST(LblLattice, DenseVoxelStaysFiniteAndNonNegative) {
  // sigma_t dx = 100 in the middle voxel (albedo 0.9): pt = 1 - exp(-100), every entry of the
  // collision stays in [0, 1]; the paper's 1 - sigma_t + sigma_s / 6 would be about -85.
  Volume v;
  v.nx = v.ny = v.nz = 8;
  v.voxel = 0.1;
  v.sigma_s.assign(3 * v.count(), 0.5f);
  v.sigma_t.assign(3 * v.count(), 1.0f);
  size_t mid = v.index(4, 4, 4);
  for (int ch = 0; ch < 3; ++ch) {
    v.sigma_t[3 * mid + ch] = 100 / 0.1f;
    v.sigma_s[3 * mid + ch] = 0.9f * 100 / 0.1f;
  }
  LatticeCoefficients c = lattice_coefficients(v, 0.0);
  EXPECT_FLOAT_EQ(c.pt[3 * mid], 1.0f);
  EXPECT_FLOAT_EQ(c.ps[3 * mid], 0.9f);
  Lattice l(cl(), c, {.blocked = true, .block = 4});
  std::vector<float> src(3 * v.count(), 0.f);
  src[3 * mid] = src[3 * mid + 1] = src[3 * mid + 2] = 1.f;
  l.set_source(src);
  l.step(400);
  double total = 0;
  for (float x : l.state()) {
    ASSERT_TRUE(std::isfinite(x));
    ASSERT_GE(x, 0.f);
    total += x;
  }
  // With open edges the lattice holds less than what was injected.
  EXPECT_GT(total, 0);
  EXPECT_LT(total, 3 * 400.0);
  for (float x : l.irradiance()) ASSERT_TRUE(std::isfinite(x) && x >= 0.f);
}

TEST(LblLattice, KernelsMatchACpuStep) {
  auto c = coefficients(8, [](int i, int j, int k) {
    float pt = 0.1f + 0.08f * ((i + 2 * j + 3 * k) % 10);
    return std::pair{pt, 0.8f * pt};
  });
  std::vector<float> src(3 * 512, 0.f);
  for (size_t i = 0; i < src.size(); i += 7) src[i] = 0.01f * (i % 13);
  std::vector<float> f0 = random_state(512, 9);
  for (auto edges : {std::array{Edge::Open, Edge::Open, Edge::Open},
                     std::array{Edge::Periodic, Edge::Reflect, Edge::Open}}) {
    std::vector<double> f(f0.begin(), f0.end()), irr;
    for (int s = 0; s < 6; ++s) cpu_step(c, src, edges, f, irr);
    for (bool blocked : {false, true}) {
      if (blocked && edges[0] == Edge::Periodic) continue;
      SCOPED_TRACE(blocked ? "blocked" : "global");
      Lattice l(cl(), c, {.blocked = blocked, .block = 4, .edges = edges});
      l.set_state(f0);
      l.set_source(src);
      l.step(6);
      std::vector<float> got = l.state(), got_irr = l.irradiance();
      for (size_t i = 0; i < f.size(); ++i)
        ASSERT_NEAR(got[i], f[i], 1e-5 * (1 + std::abs(f[i]))) << i;
      for (size_t i = 0; i < irr.size(); ++i)
        ASSERT_NEAR(got_irr[i], irr[i], 1e-5 * (1 + std::abs(irr[i]))) << i;
    }
  }
}

// The light's direction per node (Lattice::flux): m = J / phi from the mean of what arrives and
// what leaves, summed over channels, its length at most 1/3, against the same on the CPU.
TEST(LblLattice, FluxMatchesACpuComputation) {
  auto c = coefficients(8, [](int, int, int) { return std::pair{0.3f, 0.25f}; });
  std::vector<float> f0 = random_state(512, 11);
  for (float& x : f0) x = x * x * x;  // uneven enough that some nodes reach the bound
  const size_t n = 512;
  for (auto edges : {std::array{Edge::Open, Edge::Open, Edge::Open},
                     std::array{Edge::Periodic, Edge::Reflect, Edge::Open}}) {
    Lattice l(cl(), c, {.blocked = false, .edges = edges});
    l.set_state(f0);
    cl::Buffer out(cl().context(), CL_MEM_READ_WRITE, 3 * n * sizeof(float));
    l.flux(out);
    std::vector<float> got(3 * n);
    cl().queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(float), got.data());
    std::vector<double> f(f0.begin(), f0.end());
    int capped = 0;
    for (int k = 0; k < 8; ++k)
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
          size_t node = (size_t(k) * 8 + j) * 8 + i;
          double a[6][3], p[6] = {}, total = 0;
          cpu_arrivals(c, edges, f, i, j, k, a);
          for (int d = 0; d < 6; ++d) {
            for (int ch = 0; ch < 3; ++ch) p[d] += 0.5 * (a[d][ch] + f[(d * 3 + ch) * n + node]);
            total += p[d];
          }
          double m[3] = {(p[0] - p[1]) / total, (p[2] - p[3]) / total, (p[4] - p[5]) / total};
          double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
          if (len > 1.0 / 3) {
            ++capped;
            for (double& x : m) x *= 1.0 / 3 / len;
          }
          for (int ax = 0; ax < 3; ++ax) ASSERT_NEAR(got[3 * node + ax], m[ax], 1e-5) << node;
        }
    EXPECT_GT(capped, 0) << "no node reached the bound: the test does not check it";
  }
  // A uniform linearly anisotropic field, f_d = phi / 6 + (J . c_d) / 2 on every node (periodic):
  // m is J / phi exactly.
  const double phi = 6, J[3] = {0.5, -0.3, 0.2};
  std::vector<float> uniform(18 * n);
  for (int d = 0; d < 6; ++d)
    for (int ch = 0; ch < 3; ++ch)
      for (size_t node = 0; node < n; ++node)
        uniform[(d * 3 + ch) * n + node] = float((phi / 6 + ((d & 1) ? -0.5 : 0.5) * J[d / 2]) / 3);
  Lattice l(cl(), c, {.blocked = false, .edges = {Edge::Periodic, Edge::Periodic, Edge::Periodic}});
  l.set_state(uniform);
  cl::Buffer out(cl().context(), CL_MEM_READ_WRITE, 3 * n * sizeof(float));
  l.flux(out);
  std::vector<float> got(3 * n);
  cl().queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(float), got.data());
  for (size_t node = 0; node < n; ++node)
    for (int ax = 0; ax < 3; ++ax) ASSERT_NEAR(got[3 * node + ax], J[ax] / phi, 1e-6);
}

// A homogeneous cube (12^3 nodes of medium inside a 16^3 grid) lit by a source in one corner of
// it: blocks of 4^3 with 4 inner steps per launch and the global lattice converge to the same
// irradiance; with one inner step the two are the same computation.
TEST(LblLattice, BlockedAndGlobalAgreeOnAHomogeneousCube) {
  auto c = coefficients(16, [](int i, int j, int k) {
    bool in = i >= 2 && i < 14 && j >= 2 && j < 14 && k >= 2 && k < 14;
    return in ? std::pair{0.3f, 0.29f} : std::pair{0.f, 0.f};
  });
  std::vector<float> src(3 * 4096, 0.f);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j)
      for (int ch = 0; ch < 3; ++ch) src[3 * ((size_t(k) * 16 + j) * 16 + 3) + ch] = 1.f;
  auto converged = [&](LatticeOptions o) {
    Lattice l(cl(), c, o);
    l.set_source(src);
    Convergence r = l.converge(1e-6, 20000, 16);
    EXPECT_TRUE(r.converged);
    return l.irradiance();
  };
  std::vector<float> global = converged({.blocked = false});
  std::vector<float> blocked = converged({.blocked = true, .block = 4, .inner = 4});
  double diff = 0, norm = 0;
  for (size_t i = 0; i < global.size(); ++i) {
    diff += (blocked[i] - global[i]) * double(blocked[i] - global[i]);
    norm += double(global[i]) * global[i];
  }
  EXPECT_GT(norm, 0);
  EXPECT_LT(std::sqrt(diff / norm), 1e-3);

  Lattice a(cl(), c, {.blocked = false}), b(cl(), c, {.blocked = true, .block = 4, .inner = 1});
  a.set_source(src);
  b.set_source(src);
  a.step(40);
  b.step(40);
  std::vector<float> fa = a.state(), fb = b.state();
  for (size_t i = 0; i < fa.size(); ++i) ASSERT_NEAR(fa[i], fb[i], 1e-6 * (1 + fa[i])) << i;
}

// The 18-direction lattice in a closed box: diagonal packets reflect specularly at the walls and
// edges, so nothing is lost; with absorption each step keeps 1 - pt + ps.
TEST(LblLattice, EighteenDirectionsConserveEnergyInAClosedBox) {
  auto c = coefficients(8, [](int i, int j, int k) {
    float pt = 0.05f + 0.9f * ((i * 7 + j * 3 + k * 5) % 11) / 10.f;
    return std::pair{pt, pt};
  });
  for (int i = 0; i < 3 * 512; ++i) c.pt_diag[i] = c.ps_diag[i] = 0.5f * c.pt[i] + 0.2f;
  LatticeOptions o = closed(false);
  o.directions = 18;
  Lattice l(cl(), c, o);
  l.set_state(random_state(l.nodes(), 4, 18));
  double e0 = l.energy();
  for (int round = 1; round <= 4; ++round) {
    l.step(50);
    EXPECT_NEAR(l.energy(), e0, 50 * round * FLT_EPSILON * e0);
  }
  auto absorbing = coefficients(8, [](int, int, int) { return std::pair{0.3f, 0.24f}; });
  Lattice a(cl(), absorbing, o);
  a.set_state(random_state(a.nodes(), 6, 18));
  double before = a.energy();
  a.step(10);
  EXPECT_NEAR(a.energy(), before * std::pow(1 - 0.3 + 0.24, 10), 1e-5 * before);
}

// A point source in a homogeneous medium: at equal distances along an axis, (5, 0, 0), and off
// it, (3, 4, 0), the 6-direction lattice channels light along the axes; the 18-direction one
// is closer to isotropic.
TEST(LblLattice, EighteenDirectionsAreMoreIsotropic) {
  const int n = 24, c0 = 12;
  auto c = coefficients(n, [](int, int, int) { return std::pair{0.4f, 0.36f}; });
  for (size_t i = 0; i < c.pt.size(); ++i) {
    c.pt_diag[i] =
        1 - std::pow(1 - c.pt[i], std::sqrt(2.f));  // the same medium, sqrt(2) longer steps
    c.ps_diag[i] = c.pt_diag[i] * 0.9f;
    c.w_diag[i] = c.ps_diag[i] / 0.4f * c.pt[i] / std::sqrt(2.f);
  }
  std::vector<float> src(3 * size_t(n) * n * n, 0.f);
  auto at = [&](int i, int j, int k) { return 3 * ((size_t(k) * n + j) * n + i); };
  src[at(c0, c0, c0)] = 1.f;
  auto ratio = [&](int directions) {
    Lattice l(cl(), c, {.blocked = false, .directions = directions});
    l.set_source(src);
    EXPECT_TRUE(l.converge(1e-6, 20000, 16).converged);
    std::vector<float> irr = l.irradiance();
    return irr[at(c0 + 5, c0, c0)] / irr[at(c0 + 3, c0 + 4, c0)];
  };
  double six = ratio(6), eighteen = ratio(18);
  EXPECT_GT(six, 1.0);  // the axis gets more
  EXPECT_LT(std::abs(eighteen - 1), 0.5 * std::abs(six - 1));
}

TEST(LblLattice, RejectsBadShapes) {
  auto c = coefficients(6, [](int, int, int) { return std::pair{0.1f, 0.1f}; });
  EXPECT_THROW(Lattice(cl(), c, {.blocked = true, .block = 4}), std::invalid_argument);
  EXPECT_THROW(
      Lattice(cl(), c,
              {.blocked = true, .block = 2, .edges = {Edge::Periodic, Edge::Open, Edge::Open}}),
      std::invalid_argument);
  EXPECT_THROW(Lattice(cl(), c, {.blocked = true, .block = 2, .directions = 18}),
               std::invalid_argument);
  EXPECT_THROW(Lattice(cl(), c, {.blocked = false, .directions = 7}), std::invalid_argument);
}

}  // namespace
}  // namespace scatter::lbl
