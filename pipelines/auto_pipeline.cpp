#include "pipelines/auto_pipeline.hpp"

namespace scatter {

std::pair<std::string, std::string> AutoPipeline::choose(const Scene& scene, Terms terms) {
  if (!scene.medium.density->homogeneous())
    return {"reference", "inhomogeneous medium: the reference is exact; single (baked, 3-7 % off on the "
                         "benchmark scenes), psf and lbl render it faster when asked for"};
  if (scene.medium.ior != 1.0)
    return {"reference", "a dielectric boundary (ior != 1): thickness neglects Fresnel and refraction"};
  if (terms != Terms::Single)
    return {"reference", "the " + to_string(terms) + " term: the reference; lbl and psf render it faster "
                                                     "but further from it (docs/BENCHMARKS.md)"};
  Aabb b = scene.mesh->bounds();
  for (const Light& l : scene.lights)
    if (l.type != Light::Type::Directional && length(l.position - b.center()) <= length(b.size()) / 2 * 1.05)
      return {"reference", "a light inside the object's bounding sphere: no shadow map can see it"};
  return {"thickness",
          "homogeneous medium: the thickness path serves it; the optical-depth bake is skipped "
          "because a constant density needs none"};
}

Pipeline& AutoPipeline::delegate(const std::string& name) {
  auto& p = pipelines_[name];
  if (!p) p = make_pipeline(name, gpu_, cache_);
  return *p;
}

Plan AutoPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  auto [chosen, why] = choose(scene, request.terms);
  Plan inner = delegate(chosen).plan(scene, request);
  Plan p{name() + " -> " + chosen, request.terms, {{"choose", true, chosen + ": " + why}}};
  p.stages.insert(p.stages.end(), inner.stages.begin(), inner.stages.end());
  return p;
}

RenderResult AutoPipeline::render(const Scene& scene, const RenderRequest& request) {
  Plan p = plan(scene, request);
  RenderResult r = delegate(choose(scene, request.terms).first).render(scene, request);
  r.plan = std::move(p);
  return r;
}

}  // namespace scatter
