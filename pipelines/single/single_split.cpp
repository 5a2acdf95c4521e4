// The single bake's split at jumps (setting `split`, step 4b of pipelines/single/single_bake.hpp):
// a Gaussian whose support crosses a jump in the extinction (a ratio above `split`, such as the
// interfaces between layers) becomes two pieces at the same centre with the same weight, each
// clipped by the interface plane to its own side. The pieces of one sample sum to its Gaussian, so
// the partition of one is kept; each piece carries the scattering coefficient of its side and
// measures its transmittance from an anchor on its side (kernels/single/shade.cl, one-sided
// differences), so neither is smoothed across the jump. The splat clips each piece's ray
// integral at its plane (shaders/single/splat.frag).
#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <numbers>

#include "pipelines/single/bake_support.hpp"

namespace scatter::single_detail {
namespace {

struct Split {
  bool made = false;
  Vec3 n;         // the other side's direction
  double offset;  // plane: n . (x - centre) = offset (> 0: the centre is on its own side)
  Vec3 anchor;    // a point of the medium on the other side
  Vec3 cell;      // the centre of the nearest voxel across (all medium)
  // Extinction per unit medium of the own voxel (the centre's, or a shell sample's anchor's) and
  // of the nearest voxel across: the pieces' media (their sigma_s is taken from within `ratio`).
  double own, other;
};

// The interface plane in a sample's support, if a jump is there. Voxels count only where they
// are all medium (the surface's partial voxels are the mesh's, clipped by the depth peel).
Split find_split(const VoxelGrid& g, const Vec3& c, size_t cv, double s, double ratio) {
  Split out;
  // The own voxel (cv: the centre's, or a shell sample's anchor's) compared by its extinction as
  // the grid holds it (a boundary voxel's is its medium fraction's). A medium voxel of zero
  // extinction (an empty layer) splits too: any medium beside it is an infinite jump.
  if (!(g.occupancy[cv] > 0)) return out;
  const double own = extinction(g, cv);
  struct Cell {
    Vec3 d;
    double e;
    bool other;
  };
  std::vector<Cell> cells;
  double nearest = 1e30, across = 0;
  Vec3 towards;
  for_support(g, c, s, [&](size_t v, double e) {
    if (g.occupancy[v] < 0.999f) return;
    double st = extinction(g, v);
    bool other = st > ratio * own || st * ratio < own;
    Vec3 d = g.center(int(v % g.nx), int((v / g.nx) % g.ny), int(v / (size_t(g.nx) * g.ny))) - c;
    cells.push_back({d, e, other});
    if (other && dot(d, d) < nearest) {
      nearest = dot(d, d);
      towards = d;
      across = st;
    }
  });
  if (nearest >= 1e30) return out;
  // The other side nearest the centre (a layer's far interface is left to its own samples):
  // the plane's normal from the weighted centroids of that side and of the own side. The other
  // side's cells are those in front of the centre along the normal, which starts as the nearest
  // such cell's direction and is refined: that direction is diagonal unless the centre faces a
  // cell squarely, and a half-space across it keeps an oblique part of a layer, tilting the
  // plane.
  Vec3 n = towards * (1 / std::sqrt(nearest));
  for (int pass = 0; pass < 3; ++pass) {
    Vec3 so{0, 0, 0}, oo{0, 0, 0};
    double ws = 0, wo = 0;
    for (const Cell& k : cells) {
      if (k.other && dot(k.d, n) <= 0) continue;
      (k.other ? oo : so) = (k.other ? oo : so) + k.d * k.e;
      (k.other ? wo : ws) += k.e;
    }
    if (ws <= 0 || wo <= 0) return out;
    const Vec3 next = oo * (1 / wo) - so * (1 / ws);
    const double len = std::sqrt(dot(next, next));
    if (len <= 0) return out;
    n = next * (1 / len);
  }
  // The offset that best separates the two sides (fewest weighted cells on the wrong side).
  std::vector<std::pair<double, double>> proj;  // projection, +e for own, -e for other
  for (const Cell& k : cells) {
    if (k.other && dot(k.d, n) <= 0) continue;
    proj.push_back({dot(k.d, n), k.other ? -k.e : k.e});
  }
  std::sort(proj.begin(), proj.end());
  // Sweep the threshold up through the sorted projections: wrong = own above + other below.
  double own_above = 0, other_below = 0, best = 1e30, at = 0;
  for (const auto& [x, e] : proj)
    if (e > 0) own_above += e;
  for (size_t k = 0; k <= proj.size(); ++k) {
    const double err = own_above + other_below;
    if (err < best) {
      best = err;
      at = k == 0 ? proj[0].first - g.voxel / 2
                  : (k == proj.size() ? proj.back().first + g.voxel / 2
                                      : (proj[k - 1].first + proj[k].first) / 2);
    }
    if (k == proj.size()) break;
    if (proj[k].second > 0)
      own_above -= proj[k].second;
    else
      other_below -= proj[k].second;
  }
  if (at <= 0) return out;  // the centre itself would lie on the other side
  // The other side's mass of the Gaussian: too little is not worth a piece.
  const double z = at / s;
  const double mass = 0.5 * std::erfc(z / std::numbers::sqrt2);
  if (mass < 0.02) return out;
  // Its anchor: the mean of the Gaussian beyond the plane, at least half a voxel in.
  const double mean = s * std::exp(-0.5 * z * z) / std::sqrt(2 * std::numbers::pi) / mass;
  out.made = true;
  out.n = n;
  out.offset = at;
  out.anchor = c + n * std::max(mean, at + 0.5 * g.voxel);
  out.cell = c + towards;
  out.own = own / g.occupancy[cv];
  out.other = across;
  return out;
}

}  // namespace

int split_at_jumps(const VoxelGrid& g, const std::vector<uint8_t>& layer, double ratio,
                   SingleBake& bake, std::vector<float>& medium) {
  const int n = bake.count;
  bake.plane.assign(4 * size_t(n), 0.f);
  medium.clear();
  for (int i = 0; i < n; ++i) medium.insert(medium.end(), {0.f, FLT_MAX});
  if (ratio <= 1) return 0;
  std::vector<Split> splits(n);
  parallel_for(size_t(n), [&](size_t a, size_t b, size_t) {
    for (size_t i = a; i < b; ++i) {
      Vec3 c{bake.position[3 * i], bake.position[3 * i + 1], bake.position[3 * i + 2]};
      // A shell sample (outside the medium, clipped by the mesh) takes its anchor's medium as
      // its own: its Gaussian reaches in across the layers under the surface as well.
      const size_t cv = voxel_at(g, c);
      const size_t own = layer[cv] == 0
                             ? cv
                             : voxel_at(g, {bake.depth_at[3 * i], bake.depth_at[3 * i + 1],
                                            bake.depth_at[3 * i + 2]});
      splits[i] = find_split(g, c, own, bake.sigma[i], ratio);
    }
  });
  int made = 0;
  for (int i = 0; i < n; ++i) {
    const Split& s = splits[i];
    if (!s.made) continue;
    ++made;
    Vec3 c{bake.position[3 * i], bake.position[3 * i + 1], bake.position[3 * i + 2]};
    const double d = dot(s.n, c) + s.offset;
    // The sample keeps its own side: n . x <= d.
    std::copy_n(std::array<float, 4>{float(s.n.x), float(s.n.y), float(s.n.z), float(d)}.data(), 4,
                &bake.plane[4 * size_t(i)]);
    // The new piece: -n . x <= -d.
    bake.position.insert(bake.position.end(), {float(c.x), float(c.y), float(c.z)});
    // Its anchor moves with the sample's own (a shell sample measures from inside the medium; the
    // shading tests its differences against the plane moved the same way, depth_frame_planes),
    // and where that leaves the medium (a shell sample beside an edge, a thin layer's end),
    // towards the point just across the plane until it is inside, else the nearest voxel across
    // (moved, then not): the first inside the medium and across the moved plane.
    const Vec3 shift = Vec3{bake.depth_at[3 * size_t(i)], bake.depth_at[3 * size_t(i) + 1],
                            bake.depth_at[3 * size_t(i) + 2]} -
                       c;
    auto usable = [&](const Vec3& x) {
      return g.occupancy[voxel_at(g, x)] > 0 && dot(s.n, x - shift) >= d;
    };
    const Vec3 across = c + shift + s.n * (s.offset + 0.25 * g.voxel);
    Vec3 a = s.anchor + shift;
    for (int k = 0; k < 8 && !usable(a); ++k) a = (a + across) * 0.5;
    if (!usable(a)) a = usable(across) ? across : usable(s.cell + shift) ? s.cell + shift : s.cell;
    bake.depth_at.insert(bake.depth_at.end(), {float(a.x), float(a.y), float(a.z)});
    bake.sigma.push_back(bake.sigma[i]);
    bake.weight.push_back(bake.weight[i]);
    if (!bake.coarse_weight.empty()) bake.coarse_weight.push_back(bake.coarse_weight[i]);
    bake.plane.insert(bake.plane.end(), {float(-s.n.x), float(-s.n.y), float(-s.n.z), float(-d)});
    // Each piece's sigma_s from its own side's medium only: a Gaussian wider than a layer reaches
    // past the next interface too, and a piece whose mean took in the layer beyond (a dense one
    // past an empty one) would carry it into the empty layer.
    medium[2 * size_t(i)] = float(s.own / ratio);
    medium[2 * size_t(i) + 1] = float(s.own * ratio);
    medium.insert(medium.end(), {float(s.other / ratio), float(s.other * ratio)});
  }
  bake.count = n + made;
  return made;
}

std::vector<float> depth_frame_planes(const SingleBake& b) {
  std::vector<float> out = b.plane;
  const int whole = b.count - b.split;
  int piece = whole;
  for (int i = 0; i < whole && !b.plane.empty(); ++i) {
    const float* pl = &b.plane[4 * size_t(i)];
    if (pl[0] == 0 && pl[1] == 0 && pl[2] == 0) continue;
    // The sample's shift from its position to its own anchor (zero inside the medium).
    const double dx = b.depth_at[3 * size_t(i)] - b.position[3 * size_t(i)],
                 dy = b.depth_at[3 * size_t(i) + 1] - b.position[3 * size_t(i) + 1],
                 dz = b.depth_at[3 * size_t(i) + 2] - b.position[3 * size_t(i) + 2];
    for (int k : {i, piece}) {
      float* q = &out[4 * size_t(k)];
      q[3] = float(q[3] + q[0] * dx + q[1] * dy + q[2] * dz);
    }
    ++piece;
  }
  return out;
}

}  // namespace scatter::single_detail
