// Light rays for the lbl pipeline's marching pass: where they start, in which direction and with
// which power, for point, directional and spot lights; and the march that deposits the power
// they scatter into a volume (kernels/lbl/march.cl).
#pragma once

#include <vector>

#include "pipelines/lbl/volume.hpp"
#include "scene/scene.hpp"

namespace scatter::lbl {

// Floats per ray in the kernels' layout: origin, unit direction, RGB power (watts), unused.
constexpr int kRayFloats = 12;

struct RaySet {
  std::vector<float> rays;  // kRayFloats per ray
  int count() const { return static_cast<int>(rays.size() / kRayFloats); }
};

// Rays covering the volume's bounding sphere with about `per_voxel` rays per voxel width (per
// side, at most `max_side` rays per side per light). Directional lights: a square lattice of
// parallel rays on a plane before the volume, each carrying irradiance x its cross-section.
// Point and spot lights: directions spread evenly in solid angle over the cone that holds the
// volume (the whole sphere when the light is inside it), each carrying intensity x its solid
// angle (x the spot's smooth cone factor). Rays start at the light (or the plane); the march
// moves them to where they enter the grid.
RaySet light_rays(const std::vector<Light>& lights, const Volume& v, double per_voxel,
                  int max_side);

// Adds the power each ray scatters in each voxel to `deposit` (3 floats per voxel). `bend`:
// follow the ray equation in steps of `step` scene units; otherwise cross voxels exactly.
// Rays stop when their strongest channel falls under `cutoff` times its start. With g != 0 the
// delta-Eddington scaled beam's scattering (the lattice's source) goes to `source` (which may
// then not be `deposit`); with g = 0 the two are the same and `source` is not written. `flow`
// (optional, 6 floats per voxel): the scattered power summed over channels times the ray's
// direction (3 per voxel), for the view pass's phase function, then (3 per voxel, after all
// of those) what the light the scaled beam kept forward scatters (kernels/lbl/march.cl).
void march(gpu::ClContext& cl, const ClVolume& v, const cl::Buffer& rays, int count, bool bend,
           double step, double cutoff, double g, cl::Buffer& deposit, cl::Buffer& source,
           cl::Buffer* flow = nullptr);

// Positions after each of `steps` Eikonal steps of `step` scene units from each ray's origin
// (3 floats per step per ray), for tests of the integrator.
std::vector<float> eikonal_trace(gpu::ClContext& cl, const ClVolume& v, const RaySet& rays,
                                 double step, int steps);

}  // namespace scatter::lbl
