// Weighted Poisson-disk sampling by sample elimination (Yuksel 2015), which reaches a target
// count exactly: draw more candidates than wanted with a density that follows the local radius,
// then repeatedly remove the candidate whose neighbours crowd it most.
//
// Spacing is adaptive: candidate i carries a relative radius q_i (1 = the base spacing), distances
// are measured in units of the pair's mean q, and the weight of a pair is (1 - d/(2 r))^8 inside
// 2 r, with r the largest Poisson radius the normalised volume allows for `target` points.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/vec.hpp"

namespace scatter {

struct EliminationResult {
  std::vector<int> kept;   // indices into the candidates, `target` of them
  double base_radius = 0;  // r, in normalised units (world distance / mean q)
};

// `q` has one relative radius per candidate (all 1 for uniform spacing); `volume` is the region's
// volume in normalised units (sum of dV / q^3). Throws std::invalid_argument if target exceeds the
// candidates or is not positive.
// `progress` (optional) hears the fraction done now and then, and may throw to stop the work.
EliminationResult eliminate_samples(const std::vector<Vec3>& candidates,
                                    const std::vector<float>& q, double volume, int target,
                                    const std::function<void(double)>& progress = {});

// A progressive order of `points` (Yuksel 2015, section 5): repeated elimination halves the set
// down to `min_count`, each half kept ahead of the points it lost, so that every prefix of 1/2,
// 1/4, ... of the points is itself a Poisson-disk set with a radius 2^(1/3), 4^(1/3), ... times
// the whole's (and any prefix nearly so). Returns the indices in that order.
std::vector<int> progressive_order(const std::vector<Vec3>& points, const std::vector<float>& q,
                                   double volume, int min_count = 256);

// Smallest normalised distance between two kept samples: |a - b| / ((q_a + q_b) / 2).
double min_normalized_distance(const std::vector<Vec3>& points, const std::vector<float>& q);

}  // namespace scatter
