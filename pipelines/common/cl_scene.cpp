#include "pipelines/common/cl_scene.hpp"

#include <numbers>

namespace scatter {

std::vector<float> pack_lights(const std::vector<Light>& lights) {
  std::vector<float> out(16 * std::max<size_t>(lights.size(), 1), 0.f);
  const double to_rad = std::numbers::pi / 180;
  for (size_t i = 0; i < lights.size(); ++i) {
    const Light& l = lights[i];
    float* p = &out[16 * i];
    Vec3 power = l.color * l.intensity;
    for (int c = 0; c < 3; ++c) {
      p[c] = float(l.position[c]);
      p[3 + c] = float(l.direction[c]);
      p[6 + c] = float(power[c]);
    }
    p[9] = float(std::cos(l.outer_deg * to_rad));
    p[10] = float(std::cos(l.inner_deg * to_rad));
    p[11] = l.type == Light::Type::Point ? 0.f : (l.type == Light::Type::Directional ? 1.f : 2.f);
  }
  return out;
}

std::vector<float> pack_camera(const Camera& c, int width, int height) {
  CameraFrame frame = camera_frame(c, width, height);
  std::vector<float> out;
  for (const Vec3& v : {c.position, frame.forward, frame.right, frame.up})
    for (int k = 0; k < 3; ++k) out.push_back(float(v[k]));
  return out;
}

cl::Buffer upload(gpu::ClContext& cl, const std::vector<float>& data) {
  if (data.empty())
    return cl::Buffer(cl.context(), CL_MEM_READ_ONLY, sizeof(float));  // placeholder
  return cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                    std::max<size_t>(data.size(), 1) * sizeof(float),
                    const_cast<float*>(data.data()));
}

ClMedium upload_medium(gpu::ClContext& cl, const VoxelGrid& grid, int brick) {
  ClMedium m;
  std::vector<float> sigma_t(grid.sigma_s.size());
  for (size_t i = 0; i < sigma_t.size(); ++i) sigma_t[i] = grid.sigma_s[i] + grid.sigma_a[i];
  m.sigma_s = upload(cl, grid.sigma_s);
  m.sigma_t = upload(cl, sigma_t);
  m.bricks = brick_majorants(cl, grid, brick);
  m.majorant = upload(cl, m.bricks.majorant);
  m.origin = {{float(grid.origin.x), float(grid.origin.y), float(grid.origin.z)}};
  m.voxel = float(grid.voxel);
  m.nx = grid.nx;
  m.ny = grid.ny;
  m.nz = grid.nz;
  return m;
}

}  // namespace scatter
