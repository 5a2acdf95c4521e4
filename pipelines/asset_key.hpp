// The one key builder for what pipelines keep or bake per asset: the mesh (its SHA-256, computed
// once when the scene was parsed), whether the exact procedural solid bounds it, the density
// field's id (its canonical JSON's SHA-256, and a grid's data), the medium's coefficients and
// the resolution. Pipelines add what else shapes their state (g, ior, their settings from the
// settings table) and take .hex().
#pragma once

#include "bake/cache.hpp"
#include "scene/scene.hpp"

namespace scatter {

// Bump when the voxelizer's output changes for the same asset: products keyed by asset are baked
// from its voxels.
inline constexpr const char* kVoxelizerVersion = "voxelizer-1";

// A scene built in code without parse_scene has no ids: its mesh is hashed here and its density
// keyed by the object's address (the caller holds the object while it compares keys).
BakeKey asset_key(const Scene& scene);

}  // namespace scatter
