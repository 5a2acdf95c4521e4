// The `single` pipeline's setting `coarse`: which of the bake's samples a frame splats.
#include <algorithm>
#include <cmath>

#include "pipelines/single/single_pipeline.hpp"

namespace scatter {

DrawnSamples drawn_samples(const SingleBake& b, bool coarse) {
  DrawnSamples d;
  const int whole = b.count - b.split;  // the samples; their split-off pieces follow them
  const int prefix = coarse_count(whole);
  if (!coarse || prefix <= 0 || b.coarse_weight.empty()) {
    d.ranges = {{0, b.count}};
    return d;
  }
  // A split sample keeps a plane (its side of the jump), and its other piece is appended after
  // all samples in the samples' order: the pieces of the prefix's are a prefix of the pieces.
  int pieces = 0;
  if (b.split > 0)
    for (int i = 0; i < prefix; ++i)
      if (b.plane[4 * size_t(i)] != 0 || b.plane[4 * size_t(i) + 1] != 0 ||
          b.plane[4 * size_t(i) + 2] != 0)
        ++pieces;
  d.ranges = {{0, prefix}};
  if (pieces > 0) d.ranges.push_back({whole, pieces});
  d.sigma_scale = std::cbrt(double(whole) / prefix);
  d.coarse = true;
  return d;
}

}  // namespace scatter
