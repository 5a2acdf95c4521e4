#include "pipelines/asset_key.hpp"

#include <cstdint>
#include <string>

namespace scatter {

BakeKey asset_key(const Scene& scene) {
  BakeKey k;
  k.add("voxelizer", kVoxelizerVersion);
  k.add("mesh", scene.mesh_id.empty() ? mesh_digest(*scene.mesh) : scene.mesh_id);
  k.add("solid", scene.shape ? "exact shape" : "mesh");
  const DensityField& d = *scene.medium.density;
  k.add("density",
        !d.id().empty() ? d.id() : "object " + std::to_string(reinterpret_cast<uintptr_t>(&d)));
  for (int c = 0; c < 3; ++c)
    k.add("sigma_s", scene.medium.sigma_s[c]).add("sigma_a", scene.medium.sigma_a[c]);
  k.add("voxels", scene.voxels);
  return k;
}

}  // namespace scatter
