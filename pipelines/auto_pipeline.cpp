#include "pipelines/auto_pipeline.hpp"

#include "pipelines/registry.hpp"

namespace scatter {

const PipelineInfo& auto_info();

std::pair<std::string, std::string> AutoPipeline::choose(const Scene& scene, Terms terms) {
  if (!scene.medium.density->homogeneous())
    return {"reference",
            "inhomogeneous medium: the reference is exact; single (baked, 3-7 % off on the "
            "benchmark scenes), psf and lbl render it faster when asked for"};
  if (scene.medium.ior != 1.0)
    return {"reference",
            "a dielectric boundary (ior != 1): thickness neglects Fresnel and refraction"};
  if (terms != Terms::Single)
    return {"reference", "the " + to_string(terms) +
                             " term: the reference; lbl and psf render it faster "
                             "but further from it (docs/BENCHMARKS.md)"};
  Aabb b = scene.mesh->bounds();
  for (const Light& l : scene.lights)
    if (l.type != Light::Type::Directional &&
        length(l.position - b.center()) <= length(b.size()) / 2 * 1.05)
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

namespace {

// The request as the chosen pipeline gets it: its own settings only.
RenderRequest delegated(const RenderRequest& request, const std::string& chosen) {
  RenderRequest r = request;
  r.settings = AutoPipeline::settings_for(chosen, request.settings);
  return r;
}

}  // namespace

Plan AutoPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  info().validate(request.settings);
  auto [chosen, why] = choose(scene, request.terms);
  RenderRequest inner_request = delegated(request, chosen);
  Plan inner = delegate(chosen).plan(scene, inner_request);
  std::string unused;
  for (const auto& [key, value] : request.settings)
    if (!inner_request.settings.count(key)) unused += (unused.empty() ? "" : ", ") + key;
  if (!unused.empty()) why += " (settings not used by " + chosen + ": " + unused + ")";
  Plan p{name() + " -> " + chosen, request.terms, {{"choose", true, chosen + ": " + why}}};
  p.stages.insert(p.stages.end(), inner.stages.begin(), inner.stages.end());
  return p;
}

RenderResult AutoPipeline::render(const Scene& scene, const RenderRequest& request) {
  Plan p = plan(scene, request);
  const std::string chosen = choose(scene, request.terms).first;
  RenderResult r = delegate(chosen).render(scene, delegated(request, chosen));
  r.plan = std::move(p);
  return r;
}

CostEstimate AutoPipeline::estimate(const Scene& scene, const RenderRequest& request, bool bake) {
  auto_info().validate(request.settings);
  const std::string chosen = choose(scene, request.terms).first;
  // AutoPipeline::render delegates to its choice with its settings; auto bakes nothing itself.
  CostEstimate e = pipeline_info(chosen).estimate(scene, delegated(request, chosen), bake);
  e.summary = "auto -> " + e.summary;
  return e;
}

}  // namespace scatter
