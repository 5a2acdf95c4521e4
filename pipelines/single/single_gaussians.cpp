// The single bake's Gaussians (step 4 of pipelines/single/single_bake.hpp): weights normalised to
// a partition of one, coverage statistics, and each sample's sigma_s.
#include <numbers>

#include "pipelines/single/bake_support.hpp"

namespace scatter::single_detail {

namespace {

Vec3 position_of(const SingleBake& b, int i) {
  return {b.position[3 * size_t(i)], b.position[3 * size_t(i) + 1], b.position[3 * size_t(i) + 2]};
}

// The samples' weights: start from spacing^3 / Gaussian volume, then rescale each weight by the
// Gaussian-weighted mean of 1 / (sum of all Gaussians) over the voxel centres of the medium and all
// but the outermost shell layer, then weight_fit. Returns the Gaussians' sum per voxel.
std::vector<double> fit_weights(const VoxelGrid& g, const std::vector<uint8_t>& layer, int shell,
                                const SingleBakeParams& p, SingleBake& bake,
                                const std::function<void(double)>& report) {
  const size_t voxels = g.count();
  // Weights: start from spacing^3 / Gaussian volume, then rescale each weight by the
  //    Gaussian-weighted mean of 1 / (sum of all Gaussians) over the voxel centres of the medium
  //    and all but the outermost shell layer.
  const int n = bake.count;
  auto pos = [&](int i) { return position_of(bake, i); };
  bake.weight.resize(n);
  for (int i = 0; i < n; ++i) {
    double spacing = bake.sigma[i] / p.radius;
    bake.weight[i] = static_cast<float>(std::pow(spacing / bake.sigma[i], 3) /
                                        std::pow(2 * std::numbers::pi, 1.5));
  }
  std::vector<double> sum(voxels);
  const size_t threads = thread_count(size_t(n));
  std::vector<std::vector<double>> partial(threads - 1, std::vector<double>(voxels));
  auto accumulate = [&] {
    // Each thread adds its samples into its own array; the arrays are summed after.
    parallel_for(
        size_t(n),
        [&](size_t a, size_t b, size_t t) {
          std::vector<double>& out = t == 0 ? sum : partial[t - 1];
          std::fill(out.begin(), out.end(), 0.0);
          for (size_t i = a; i < b; ++i)
            for_support(g, pos(int(i)), bake.sigma[i],
                        [&](size_t v, double e) { out[v] += bake.weight[i] * e; });
        },
        threads);
    for (const auto& part : partial)
      for (size_t v = 0; v < voxels; ++v) sum[v] += part[v];
  };
  for (int pass = 0; pass < 4; ++pass) {
    accumulate();
    parallel_for(size_t(n), [&](size_t a, size_t b, size_t) {
      for (size_t i = a; i < b; ++i) {
        double num = 0, den = 0;
        for_support(g, pos(int(i)), bake.sigma[i], [&](size_t v, double e) {
          if (layer[v] >= shell) return;
          num += e;
          den += e * sum[v];
        });
        if (den > 0) bake.weight[i] = static_cast<float>(bake.weight[i] * num / den);
      }
    });
    report((pass + 1) / 5.0);
  }
  // weight_fit: conjugate-gradient least squares (CGLS) on min sum_v (sum_i w_i G_i(v) - 1)^2 over
  // the same voxels, from the passes' weights; the multiplicative passes converge slowly (a
  // pointwise spread of ~9 % after 4 passes, ~6.5 % after 64).
  if (p.weight_fit > 0) {
    auto fitted = [&](size_t v) { return layer[v] < shell; };
    // out = A x (per voxel), restricted to the fitted voxels (the threads' arrays are
    // accumulate's).
    auto apply = [&](const std::vector<double>& x, std::vector<double>& out) {
      parallel_for(
          size_t(n),
          [&](size_t a, size_t b, size_t t) {
            std::vector<double>& o = t == 0 ? out : partial[t - 1];
            std::fill(o.begin(), o.end(), 0.0);
            for (size_t i = a; i < b; ++i)
              for_support(g, pos(int(i)), bake.sigma[i],
                          [&](size_t v, double e) { o[v] += x[i] * e; });
          },
          threads);
      for (const auto& part : partial)
        for (size_t v = 0; v < voxels; ++v) out[v] += part[v];
      for (size_t v = 0; v < voxels; ++v)
        if (!fitted(v)) out[v] = 0;
    };
    // out = A^T r (per sample).
    auto adjoint = [&](const std::vector<double>& r, std::vector<double>& out) {
      parallel_for(size_t(n), [&](size_t a, size_t b, size_t) {
        for (size_t i = a; i < b; ++i) {
          double acc = 0;
          for_support(g, pos(int(i)), bake.sigma[i], [&](size_t v, double e) { acc += e * r[v]; });
          out[i] = acc;
        }
      });
    };
    auto norm2 = [](const std::vector<double>& x) {
      double s = 0;
      for (double v : x) s += v * v;
      return s;
    };
    std::vector<double> w(bake.weight.begin(), bake.weight.end()), dir;
    std::vector<double> r(voxels), q(voxels), s(static_cast<size_t>(n));
    apply(w, r);
    for (size_t v = 0; v < voxels; ++v) r[v] = fitted(v) ? 1.0 - r[v] : 0.0;
    adjoint(r, s);
    dir = s;
    double gamma = norm2(s);
    for (int it = 0; it < p.weight_fit && gamma > 0; ++it) {
      apply(dir, q);
      const double qq = norm2(q);
      if (qq <= 0) break;
      const double alpha = gamma / qq;
      for (int i = 0; i < n; ++i) w[i] += alpha * dir[i];
      for (size_t v = 0; v < voxels; ++v) r[v] -= alpha * q[v];
      adjoint(r, s);
      const double next = norm2(s);
      for (int i = 0; i < n; ++i) dir[i] = s[i] + next / gamma * dir[i];
      gamma = next;
      report(0.8 +
             0.15 * (it + 1) / p.weight_fit);  // progress (and a cancel's chance) per iteration
    }
    // A Gaussian with a negative weight would subtract light: keep them non-negative.
    for (int i = 0; i < n; ++i) bake.weight[i] = static_cast<float>(std::max(0.0, w[i]));
  }
  accumulate();
  return sum;
}

}  // namespace

void make_gaussians(const VoxelGrid& g, const std::vector<uint8_t>& layer, int shell,
                    const SingleBakeParams& p, SingleBake& bake,
                    const std::function<void(double)>& report) {
  const size_t voxels = g.count();
  const int n = bake.count;
  auto pos = [&](int i) { return position_of(bake, i); };
  const size_t threads = thread_count(size_t(n));
  std::vector<double> sum =
      fit_weights(g, layer, shell, p, bake, [&](double f) { report(0.8 * f); });
  // The coarse set (setting `coarse`): the first quarter of the samples, which their progressive
  // order makes Poisson-disk, widened to fill the same volume, with weights fitted for them.
  const int coarse = coarse_count(n);
  bake.coarse_weight.clear();
  if (coarse > 0) {
    SingleBake c;
    c.count = coarse;
    c.position.assign(bake.position.begin(), bake.position.begin() + 3 * size_t(coarse));
    const double widen = std::cbrt(double(n) / coarse);
    for (int i = 0; i < coarse; ++i) c.sigma.push_back(float(bake.sigma[size_t(i)] * widen));
    SingleBakeParams cp = p;
    cp.weight_fit = std::min(p.weight_fit, 10);
    fit_weights(g, layer, shell, cp, c, [&](double f) { report(0.8 + 0.05 * f); });
    bake.coarse_weight = std::move(c.weight);
    bake.coarse_weight.resize(size_t(n), 0.f);
  }
  double s1 = 0, s2 = 0, cnt = 0;
  for (size_t v = 0; v < voxels; ++v)
    if (g.inside[v]) {
      s1 += sum[v];
      s2 += sum[v] * sum[v];
      cnt += 1;
    }
  bake.coverage_mean = cnt > 0 ? s1 / cnt : 0;
  bake.coverage_spread =
      cnt > 0 ? std::sqrt(std::max(0.0, s2 / cnt - bake.coverage_mean * bake.coverage_mean)) /
                    std::max(1e-30, bake.coverage_mean)
              : 0;
  // Pieces at jumps (pipelines/single/single_split.cpp); from here on a piece's Gaussian counts
  // only on its side of its plane.
  std::vector<float> medium;
  bake.split = split_at_jumps(g, layer, p.split, bake, medium);
  const int pieces = bake.count;
  // Whether voxel v's medium (extinction per unit medium) is piece i's to take sigma_s from.
  auto own_medium = [&](int i, size_t v) {
    const double o = g.occupancy[v];
    if (!(o > 0)) return false;
    const double e = extinction(g, v) / o;
    return e >= medium[2 * size_t(i)] && e <= medium[2 * size_t(i) + 1];
  };
  auto for_piece = [&](int i, auto&& f) {
    const float* pl = &bake.plane[4 * size_t(i)];
    const Vec3 nrm{pl[0], pl[1], pl[2]};
    for_support(g, pos(i), bake.sigma[i], [&](size_t v, double e) {
      const Vec3 x =
          g.center(int(v % g.nx), int((v / g.nx) % g.ny), int(v / (size_t(g.nx) * g.ny)));
      if (dot(nrm, x) <= pl[3]) f(v, e);
    });
  };
  // Each sample's sigma_s: the Gaussian-weighted mean of the medium (boundary voxels hold
  // sigma_s times their medium fraction, so the mean divides by the weighted occupancy).
  bake.sigma_s.assign(3 * size_t(pieces), 0.f);
  parallel_for(size_t(pieces), [&](size_t a, size_t b, size_t) {
    for (size_t i = a; i < b; ++i) {
      double acc[3] = {0, 0, 0}, occ = 0;
      for_piece(int(i), [&](size_t v, double e) {
        if (!own_medium(int(i), v)) return;
        for (int c = 0; c < 3; ++c) acc[c] += e * g.sigma_s[3 * v + c];
        occ += e * g.occupancy[v];
      });
      for (int c = 0; c < 3; ++c)
        bake.sigma_s[3 * i + c] = occ > 0 ? static_cast<float>(acc[c] / occ) : 0.f;
    }
  });
  // sigma_fit passes (Landweber iterations) move each sample's sigma_s by the Gaussian-weighted
  // mean residual of the splatted field sum_i w_i sigma_i G_i against the voxels (per unit medium:
  // a boundary voxel's sigma_s holds its medium fraction, so the field is compared times the
  // occupancy). The plain mean smooths a jump in sigma_s over the larger Gaussians of the sparser
  // side (layers: 2x too bright next to a dense layer); the passes sharpen it back. Measured in
  // docs/BENCHMARKS.md; more than a few passes overshoot at the jumps.
  {
    const int fit_passes = p.sigma_fit;
    std::vector<double> field(3 * voxels);
    std::vector<std::vector<double>> fpart(threads - 1, std::vector<double>(3 * voxels));
    for (int pass = 0; pass < fit_passes; ++pass) {
      parallel_for(
          size_t(pieces),
          [&](size_t a, size_t b, size_t t) {
            std::vector<double>& out = t == 0 ? field : fpart[t - 1];
            std::fill(out.begin(), out.end(), 0.0);
            for (size_t i = a; i < b; ++i)
              for_piece(int(i), [&](size_t v, double e) {
                for (int c = 0; c < 3; ++c)
                  out[3 * v + c] += bake.weight[i] * e * bake.sigma_s[3 * i + c];
              });
          },
          threads);
      for (const auto& part : fpart)
        for (size_t v = 0; v < 3 * voxels; ++v) field[v] += part[v];
      parallel_for(size_t(pieces), [&](size_t a, size_t b, size_t) {
        for (size_t i = a; i < b; ++i) {
          double acc[3] = {0, 0, 0}, occ = 0;
          for_piece(int(i), [&](size_t v, double e) {
            double o = g.occupancy[v];
            if (o <= 0 || !own_medium(int(i), v)) return;
            for (int c = 0; c < 3; ++c) acc[c] += e * (g.sigma_s[3 * v + c] - o * field[3 * v + c]);
            occ += e * o;
          });
          if (occ > 0)
            for (int c = 0; c < 3; ++c)
              bake.sigma_s[3 * i + c] =
                  static_cast<float>(std::max(0.0, bake.sigma_s[3 * i + c] + acc[c] / occ));
        }
      });
    }
  }
}

}  // namespace scatter::single_detail
