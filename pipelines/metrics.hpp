// Image error measures used by tests and benchmarks (DESIGN: relative RMSE over the pixels the
// medium covers, on linear radiance).
#pragma once

#include <cstdint>
#include <vector>

#include "pipelines/image.hpp"
#include "scene/scene.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

// 1 for pixels whose camera ray (through the pixel centre) crosses a voxel with occupancy > 0.
std::vector<uint8_t> coverage_mask(const Scene& scene, const VoxelGrid& grid);

// ||a - ref||_2 / ||ref||_2 over the masked pixels, all channels. Throws std::invalid_argument
// when the sizes differ or the reference is zero there.
double relative_rmse(const Image& a, const Image& ref, const std::vector<uint8_t>& mask);

// ||e||_2 / ||ref||_2 over the masked pixels: e.g. a Monte Carlo reference's own noise level.
double relative_norm(const Image& e, const Image& ref, const std::vector<uint8_t>& mask);
// The same over every pixel: a render's own noise level (pixels the medium does not cover are 0
// in both).
double relative_norm(const Image& e, const Image& ref);

// How far the squared error one image reaches scatters about its expectation, relative to it,
// when each pixel's error is normal with standard deviation `std_error`:
// sqrt(2 sum_p s_p^2) / sum_p s_p, s_p the pixel's squared standard errors summed over its
// channels (one error for the three, the larger case: a grey medium's channels come from the
// same paths). sqrt(2 / N) for N equally noisy pixels, sqrt(2) when one pixel carries all the
// noise; 0 for an image without noise.
double error_scatter(const Image& std_error);

}  // namespace scatter
