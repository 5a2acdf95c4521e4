// ThicknessPipeline::estimate and SurfacePipeline::estimate: the distance maps and render
// targets they draw (pipelines/common/raster.cpp's RenderTarget: RGBA32F colour + 32F depth).
#include <algorithm>

#include "pipelines/cost_support.hpp"
#include "pipelines/surface/surface_pipeline.hpp"
#include "pipelines/thickness/thickness_pipeline.hpp"

namespace scatter {
namespace {

// RenderTarget: 16 B colour + 4 B depth a texel (glTexStorage2D in raster.cpp).
constexpr double kTargetBytes = 20;

std::string pixels_text(const Scene& scene) {
  return std::to_string(scene.width) + "x" + std::to_string(scene.height) + " px";
}

// MeshBuffers (raster.cpp): interleaved positions and normals on the host and in a GL buffer,
// and the indices.
void add_mesh(cost::Ledger& l, const Scene& scene) {
  double bytes = double(scene.mesh->positions.size()) * 24 + double(scene.mesh->indices.size()) * 4;
  l.host("scene.mesh", bytes, "mesh upload");
  l.device("scene.mesh", bytes, "mesh buffers");
}

// One distance map per light, all alive until the frame ends (the `shadows` / `maps` vectors).
void add_shadow_maps(cost::Ledger& l, const Scene& scene, int size, double ns_per_texel) {
  const double lights = double(scene.lights.size()), texels = double(size) * size;
  const std::string what =
      std::to_string(scene.lights.size()) + " lights x " + std::to_string(size) + "^2 texels";
  l.device("settings.shadow_size", lights * texels * kTargetBytes, what + " x 20 B");
  l.time("settings.shadow_size", lights * texels * ns_per_texel * 1e-9, what + " drawn");
}

}  // namespace

CostEstimate ThicknessPipeline::estimate(const Scene& scene, const RenderRequest& request,
                                         bool bake) {
  using namespace cost;
  ThicknessSettings s = ThicknessSettings::read(request.settings);
  Ledger l;
  if (bake) return l.finish("thickness");  // needs no bake
  const double px = double(scene.width) * scene.height;
  add_mesh(l, scene);
  // Measured: 16 lights x 2048^2: 1.48 s (22 ns a texel), 16 x 1024^2: 0.33 s; RSS +80 MB a
  // light at 2048^2 (84 MB estimated).
  add_shadow_maps(l, scene, s.shadow_size, 40);
  // front, back, out (RenderTarget each); read_color's RGBA floats and the image on the host.
  l.device("scene.image.width", px * 3 * kTargetBytes, pixels_text(scene) + " x 3 targets x 20 B");
  l.host("scene.image.width", px * 28, pixels_text(scene) + " x 28 B (read-back)");
  // Integrate: steps x lights lookups a pixel. Measured: 512^2 x 32 steps x 16 lights 2.2 s
  // (16 ns a unit); depth peel and read-back 1024^2: 0.16 s (150 ns a pixel).
  const double lights = std::max<size_t>(scene.lights.size(), 1);
  l.time("settings.steps", px * s.steps * lights * 30e-9,
         pixels_text(scene) + " x " + std::to_string(s.steps) + " steps x " +
             std::to_string(int(lights)) + " lights");
  l.time("scene.image.width", px * 300e-9, pixels_text(scene) + " peeled and read back");
  return l.finish("thickness");
}

CostEstimate SurfacePipeline::estimate(const Scene& scene, const RenderRequest& request,
                                       bool bake) {
  using namespace cost;
  SurfaceSettings s = SurfaceSettings::read(request.settings);
  Ledger l;
  if (bake) return l.finish("surface");
  const double px = double(scene.width) * scene.height;
  add_mesh(l, scene);
  // Measured: 16 lights x 2048^2 1.9 s (29 ns a texel); RSS as thickness's.
  if (s.shadows) add_shadow_maps(l, scene, s.shadow_size, 50);
  l.device("scene.image.width", px * kTargetBytes, pixels_text(scene) + " x 20 B");
  l.host("scene.image.width", px * 28, pixels_text(scene) + " x 28 B (read-back)");
  // Raster: the triangles, and the pixels shaded by every light.
  const double lights = std::max<size_t>(scene.lights.size(), 1);
  l.time("scene.image.width",
         px * (300e-9 + lights * 20e-9) + double(scene.mesh->triangle_count()) * 1e-6,
         pixels_text(scene) + " rasterised");
  return l.finish("surface");
}

}  // namespace scatter
