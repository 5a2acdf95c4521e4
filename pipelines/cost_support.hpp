// Pieces the per-pipeline cost estimates share (pipelines/cost.hpp): the voxel grid a scene will
// voxelize to, the bytes and seconds of voxelizing and uploading it, the share of pixels the
// object covers, and a ledger of named terms that picks the field driving memory or time.
#pragma once

#include <string>
#include <vector>

#include "pipelines/cost.hpp"

namespace scatter::cost {

class Ledger;

// The grid voxelize(scene, {.resolution = scene.voxels, .margin = margin}) makes
// (scene/voxelizer.cpp: ceil(side / voxel) + 2 margin per axis), padded to whole `block`s.
struct GridShape {
  int nx = 0, ny = 0, nz = 0;
  double voxel = 0;    // scene units
  double longest = 0;  // the solid's longest side, scene units
  double count() const { return double(nx) * ny * nz; }
  std::string text() const;  // "66x66x66"
};
GridShape grid_shape(const Scene& scene, int margin, int block = 1);

// Host bytes per voxel of a VoxelGrid (scene/voxelizer.hpp: sigma_s 3 floats, sigma_a 3 floats,
// occupancy 1 float, inside 1 byte) and the voxelizer's class array (1 byte, scene/voxelizer.cpp).
constexpr double kGridBytes = 29;
constexpr double kVoxelizeTransient = 1;

// Seconds to voxelize and to upload_medium() (pipelines/common/cl_scene.cpp: sigma_t on the host,
// the brick majorants in OpenCL) a grid of `voxels` voxels; measured on sphere and bunny (64-256).
double voxelize_seconds(const Scene& scene, double voxels);
double upload_seconds(double voxels);

// The peak of voxelize() then upload_medium() (pipelines/common/cl_scene.cpp), as reference and
// psf run them: the VoxelGrid, sigma_t on the host, the sigma_s and sigma_t buffers and
// brick_majorants' (pipelines/common/grid_ops.cpp) transient copies of sigma_s and sigma_a; and
// its time.
void add_medium_upload(Ledger& l, const Scene& scene, const GridShape& g);

// Share of the image the object covers at most (at least 1 %): a sphere shape's disc, else its
// bounding box's circumscribed sphere's disc or the box's projected hull, whichever is smaller.
double coverage(const Scene& scene);

// The largest extinction and scattering coefficient (per scene unit, strongest channel), the
// mean extinction and the largest single-scattering albedo in the medium, from the
// coefficients and the density sampled on a 5^3 lattice over the bounds (blockers excluded).
struct MediumBounds {
  double sigma_t = 0, sigma_s = 0, mean_sigma_t = 0, albedo = 0;
};
MediumBounds medium_bounds(const Scene& scene);

// "12.1 GB", "340 MB".
std::string bytes_text(double bytes);
std::string seconds_text(double seconds);

// Named terms of one phase of a render (what is alive together at its peak), and of its time.
class Ledger {
 public:
  // `what` says how the bytes arise: "514^3 voxels x 89 B".
  void host(const std::string& field, double bytes, const std::string& what);
  void device(const std::string& field, double bytes, const std::string& what);
  void time(const std::string& field, double seconds, const std::string& what);
  double bytes() const;
  // Keeps the phase with more bytes (its terms name the memory field); times add up.
  void peak_of(const Ledger& other);
  CostEstimate finish(const std::string& pipeline) const;

 private:
  struct Term {
    std::string field, what;
    double amount = 0;
    bool device = false;
  };
  std::vector<Term> memory_, time_;
};

}  // namespace scatter::cost
