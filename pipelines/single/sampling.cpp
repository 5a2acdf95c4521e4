#include "pipelines/single/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <unordered_map>

namespace scatter {
namespace {

// Buckets points in cubic cells for neighbour queries.
class HashGrid {
 public:
  HashGrid(const std::vector<Vec3>& points, double cell) : cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i)
      cells_[key(points[i])].push_back(static_cast<int>(i));
  }
  template <class F>
  void near(const Vec3& p, F&& f) const {
    auto [x, y, z] = coords(p);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = cells_.find(pack(x + dx, y + dy, z + dz));
          if (it == cells_.end()) continue;
          for (int j : it->second) f(j);
        }
  }

 private:
  std::tuple<int64_t, int64_t, int64_t> coords(const Vec3& p) const {
    return {int64_t(std::floor(p.x / cell_)), int64_t(std::floor(p.y / cell_)),
            int64_t(std::floor(p.z / cell_))};
  }
  static uint64_t pack(int64_t x, int64_t y, int64_t z) {
    auto u = [](int64_t v) { return uint64_t(v + (1 << 20)) & 0x1fffff; };
    return (u(x) << 42) | (u(y) << 21) | u(z);
  }
  uint64_t key(const Vec3& p) const {
    auto [x, y, z] = coords(p);
    return pack(x, y, z);
  }
  double cell_;
  std::unordered_map<uint64_t, std::vector<int>> cells_;
};

}  // namespace

EliminationResult eliminate_samples(const std::vector<Vec3>& candidates,
                                    const std::vector<float>& q, double volume, int target,
                                    const std::function<void(double)>& progress) {
  const int m = static_cast<int>(candidates.size());
  if (target <= 0)
    throw std::invalid_argument("sample elimination: the target count must be positive");
  if (target > m)
    throw std::invalid_argument("sample elimination: " + std::to_string(target) +
                                " samples wanted from " + std::to_string(m) + " candidates");
  if (q.size() != candidates.size())
    throw std::invalid_argument("sample elimination: one radius per candidate");
  EliminationResult result;
  // Largest Poisson radius for `target` points in 3D (Yuksel's r_max, from the densest packing),
  // and his lower clamp r_min (weight limiting), which keeps very close pairs from dominating.
  const double r_max = std::cbrt(volume / (4 * std::sqrt(2.0) * target));
  const double r_min = r_max * 0.65 * (1 - std::pow(double(target) / m, 1.5));
  result.base_radius = r_max;
  const float q_max = *std::max_element(q.begin(), q.end());
  HashGrid grid(candidates, 2 * r_max * q_max);

  // Neighbour lists with pair weights, and each candidate's total.
  std::vector<std::vector<std::pair<int, float>>> neighbours(m);
  std::vector<double> weight(m, 0.0);
  for (int i = 0; i < m; ++i) {
    if (progress && i % 8192 == 0) progress(0.5 * i / m);
    grid.near(candidates[i], [&](int j) {
      if (j == i) return;
      double scale = 0.5 * (q[i] + q[j]);
      double d = length(candidates[i] - candidates[j]) / scale;
      if (d >= 2 * r_max) return;
      d = std::max(
          d,
          2 * r_min);  // Yuksel's weight limiting: distances below d_min = 2 r_min count as d_min
      float w = static_cast<float>(std::pow(1 - d / (2 * r_max), 8));
      neighbours[i].push_back({j, w});
      weight[i] += w;
    });
  }

  // Max-heap with lazy deletion: an entry is current when its weight matches the candidate's.
  std::vector<char> removed(m, 0);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry> heap;
  for (int i = 0; i < m; ++i) heap.push({weight[i], i});
  int left = m;
  while (left > target) {
    auto [w, i] = heap.top();
    heap.pop();
    if (removed[i] || w != weight[i]) continue;
    removed[i] = 1;
    --left;
    if (progress && left % 8192 == 0) progress(0.5 + 0.5 * double(m - left) / (m - target));
    for (auto [j, wij] : neighbours[i]) {
      if (removed[j]) continue;
      weight[j] -= wij;
      heap.push({weight[j], j});
    }
  }
  result.kept.reserve(target);
  for (int i = 0; i < m; ++i)
    if (!removed[i]) result.kept.push_back(i);
  return result;
}

std::vector<int> progressive_order(const std::vector<Vec3>& points, const std::vector<float>& q,
                                   double volume, int min_count) {
  const int n = static_cast<int>(points.size());
  std::vector<int> order(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) order[size_t(i)] = i;
  // order[0, left) is the set still being halved; order[left, n) the points already lost, the
  // latest losses first.
  int left = n;
  std::vector<Vec3> set_points = points;
  std::vector<float> set_q = q;
  while (left / 2 >= std::max(min_count, 1)) {
    const int half = left / 2;
    EliminationResult kept = eliminate_samples(set_points, set_q, volume, half);
    std::vector<char> in(static_cast<size_t>(left), 0);
    for (int k : kept.kept) in[size_t(k)] = 1;
    std::vector<int> next;
    next.reserve(static_cast<size_t>(left));
    for (int k : kept.kept) next.push_back(order[size_t(k)]);
    for (int k = 0; k < left; ++k)
      if (!in[size_t(k)]) next.push_back(order[size_t(k)]);
    std::copy(next.begin(), next.end(), order.begin());
    left = half;
    set_points.resize(size_t(left));
    set_q.resize(size_t(left));
    for (int k = 0; k < left; ++k) {
      set_points[size_t(k)] = points[size_t(order[size_t(k)])];
      set_q[size_t(k)] = q[size_t(order[size_t(k)])];
    }
  }
  return order;
}

double min_normalized_distance(const std::vector<Vec3>& points, const std::vector<float>& q) {
  if (points.size() < 2) return INFINITY;
  Aabb box;
  for (const Vec3& p : points) box.add(p);
  // A cell of roughly two points on average finds every nearest pair within its 27 neighbours
  // often enough; fall back to growing the cell until some pair is found.
  double cell =
      std::cbrt(std::max(1e-30, box.size().x * box.size().y * box.size().z) / points.size()) * 2;
  const float q_max = *std::max_element(q.begin(), q.end());
  for (;; cell *= 2) {
    HashGrid grid(points, cell);
    double best = INFINITY;
    for (size_t i = 0; i < points.size(); ++i)
      grid.near(points[i], [&](int j) {
        if (size_t(j) <= i) return;
        best =
            std::min(best, length(points[i] - points[size_t(j)]) / (0.5 * (q[i] + q[size_t(j)])));
      });
    // Any pair closer than cell / q_max lies in neighbouring cells, so `best` is exact then.
    if (best * q_max <= cell) return best;
  }
}

}  // namespace scatter
