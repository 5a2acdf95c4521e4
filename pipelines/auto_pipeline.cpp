#include "pipelines/auto_pipeline.hpp"

#include <cmath>

#include "bake/cache.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

const PipelineInfo& auto_info();

BudgetChoice AutoPipeline::choose(const Scene& scene, const RenderRequest& request,
                                  const IsBaked& baked) {
  Budget budget{request.max_error.value_or(kDefaultMaxError), !request.max_error};
  return plan_budget(scene, request.terms, budget, request.settings, CalibrationTable::shipped(),
                     baked);
}

Pipeline& AutoPipeline::delegate(const std::string& name) {
  auto& p = pipelines_[name];
  if (!p) p = make_pipeline(name, gpu_, cache_);
  return *p;
}

IsBaked AutoPipeline::baked_in_cache(const Scene& scene) {
  return [this, &scene](const std::string& pipeline, Terms terms, const Settings& settings) {
    const PipelineInfo& info = pipeline_info(pipeline);
    if (info.bakes())
      return cache_ && info.bake_key && cache_->get(info.bake_key(scene, settings)).has_value();
    // A delegate that keeps state between frames (lbl), made by an earlier frame of this auto.
    auto p = pipelines_.find(pipeline);
    return p != pipelines_.end() && p->second && p->second->keeps(scene, {terms, settings, {}});
  };
}

RenderRequest AutoPipeline::part_request(const BudgetChoice& c, size_t part,
                                         const RenderRequest& r) {
  RenderRequest p{c.way.parts[part].terms, c.settings[part], r.progress};
  if (c.sampled && part + 1 == c.way.parts.size()) {
    p.max_error = r.max_error.value_or(kDefaultMaxError);
    p.soft_budget = !r.max_error;
  }
  p.time_limit_s = r.time_limit_s;  // counted from the request's start, whatever came before
  p.started = r.started;
  return p;
}

Plan AutoPipeline::describe(const Scene& scene, const RenderRequest& request, const BudgetChoice& c,
                            std::vector<size_t>* starts) {
  Plan p{name() + " -> " + c.way.id(), request.terms, {{"choose", true, c.reason}}};
  if (c.way.parts.size() == 2)
    p.stages.push_back({"composite", true,
                        "the single term from " + c.way.parts[0].pipeline +
                            " plus the multiple term from " + c.way.parts[1].pipeline});
  for (size_t i = 0; i < c.way.parts.size(); ++i) {
    if (starts) starts->push_back(p.stages.size());
    Plan inner = delegate(c.way.parts[i].pipeline).plan(scene, part_request(c, i, request));
    for (StagePlan s : inner.stages) {
      if (c.way.parts.size() == 2) s.name = c.way.parts[i].pipeline + "." + s.name;
      p.stages.push_back(std::move(s));
    }
  }
  p.expected_error = c.expected_error;
  p.expected_seconds = c.expected_seconds;
  p.alternatives = c.alternatives;
  return p;
}

Plan AutoPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  info().validate(request.settings);
  return describe(scene, request, choose(scene, request, baked_in_cache(scene)));
}

RenderResult AutoPipeline::render(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  info().validate(request.settings);
  BudgetChoice c = choose(scene, request, baked_in_cache(scene));
  std::vector<size_t> starts;  // where each part's stages begin in plan.stages
  Plan plan = describe(scene, request, c, &starts);
  starts.push_back(plan.stages.size());
  RenderResult out;
  for (size_t i = 0; i < c.way.parts.size(); ++i) {
    RenderResult r = delegate(c.way.parts[i].pipeline).render(scene, part_request(c, i, request));
    const std::string prefix = c.way.parts.size() == 2 ? c.way.parts[i].pipeline + "." : "";
    for (StageTime t : r.timings) {
      t.stage = prefix + t.stage;
      out.timings.push_back(std::move(t));
    }
    // What the part found while rendering (the path tracer: the samples it drew and its
    // standard error) replaces what it planned, among its own stages.
    for (const StagePlan& s : r.plan.stages)
      for (size_t k = starts[i]; k < starts[i + 1]; ++k)
        if (plan.stages[k].name == prefix + s.name) {
          plan.stages[k].run = s.run;
          plan.stages[k].reason = s.reason;
          break;
        }
    if (i == 0) {
      out.image = std::move(r.image);
      out.std_error = std::move(r.std_error);
      out.error_estimate = r.error_estimate;
      continue;
    }
    for (size_t k = 0; k < out.image.rgb.size(); ++k) out.image.rgb[k] += r.image.rgb[k];
    // Independent estimates: standard errors add in quadrature (a deterministic part has none).
    if (out.std_error && r.std_error) {
      for (size_t k = 0; k < out.std_error->rgb.size(); ++k)
        out.std_error->rgb[k] = std::hypot(out.std_error->rgb[k], r.std_error->rgb[k]);
    } else if (r.std_error) {
      out.std_error = std::move(r.std_error);
    }
  }
  if (out.std_error) {  // the path tracer's: its measured standard error
    out.error_estimate = relative_norm(*out.std_error, out.image);
  } else {
    out.error_estimate = c.expected_error;  // calibrated
  }
  out.plan = std::move(plan);
  return out;
}

CostEstimate AutoPipeline::estimate(const Scene& scene, const RenderRequest& request, bool bake) {
  auto_info().validate(request.settings);
  BudgetChoice c = choose(scene, request);
  CostEstimate e;
  for (size_t i = 0; i < c.way.parts.size(); ++i) {
    RenderRequest r = part_request(c, i, request);
    CostEstimate p = pipeline_info(c.way.parts[i].pipeline).estimate(scene, r, bake);
    if (p.bytes() > e.bytes()) {
      e.host_bytes = p.host_bytes;
      e.device_bytes = p.device_bytes;
      e.memory_field = p.memory_field;
    }
    if (p.seconds > e.seconds) e.time_field = p.time_field;
    e.seconds += p.seconds;
    e.summary += (e.summary.empty() ? "" : "; ") + p.summary;
  }
  // The budget drives the reference's samples.
  if (c.sampled && e.time_field == "settings.spp") e.time_field = "quality.max_error";
  e.summary = "auto -> " + c.way.id() + ": " + e.summary;
  return e;
}

}  // namespace scatter
