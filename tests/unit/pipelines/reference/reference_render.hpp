// What the reference pipeline's tests share: a render with settings, and a shipped scene at a
// test's size.
#pragma once

#include "../../test_util.hpp"
#include "pipelines/reference/reference_pipeline.hpp"

namespace scatter::test {

inline RenderResult reference_render(const Scene& scene, Terms terms, Settings settings = {}) {
  ReferencePipeline p(shared_gpu());
  return p.render(scene, {terms, std::move(settings)});
}

// scenes/NAME.json at size x size pixels and `voxels` on the long side.
inline Scene small_scene(const std::string& name, int size, int voxels) {
  Scene s = load_scene(source_path("scenes/" + name + ".json"));
  s.width = s.height = size;
  s.voxels = voxels;
  return s;
}

}  // namespace scatter::test
