#include "server/refine.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "pipelines/budget/calibration.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/image.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"

namespace scatter::server {
namespace {

// A multiple of 3 in [kMinPassSpp, kMaxPassSpp], nearest `spp`.
int round_spp(double spp) {
  double thirds = std::clamp(std::round(spp / 3), kMinPassSpp / 3.0, kMaxPassSpp / 3.0);
  return 3 * static_cast<int>(thirds);
}

// Whether the server's limits allow rendering `settings` (a pipeline's cost estimate; settings the
// pipeline rejects are not rendered either).
bool affordable(const std::string& pipeline, const Scene& scene, Terms terms,
                const Settings& settings, const RefineOptions& o) {
  RenderRequest r;
  r.terms = terms;
  r.settings = settings;
  try {
    CostEstimate c = estimate_cost(pipeline, scene, r);
    return (o.max_render_s <= 0 || c.seconds <= o.max_render_s) &&
           (o.step_max_s <= 0 || c.seconds <= o.step_max_s) &&
           (o.max_request_mb <= 0 || c.bytes() / double(1 << 20) <= o.max_request_mb);
  } catch (const ValidationError&) {
    return false;
  }
}

// The seconds a reference render took sampling ("trace") and doing the rest, from its stage
// timings (a scene load is not rendering).
std::pair<double, double> pass_seconds(const RenderResult& r) {
  double trace = 0, other = 0;
  for (const auto& t : r.timings)
    (t.stage == "trace" ? trace : other) += t.stage == "scene_load" ? 0 : t.ms / 1000;
  return {trace, other};
}

// The error a frame without an estimate (an approximation outside auto's calibration) is taken
// to have when a reference pass is weighed against it: noisier passes are not sent over it.
constexpr double kAssumedError = 0.1;

}  // namespace

bool worth_sending(std::optional<double> estimate, std::optional<double> last_sent) {
  return !estimate || !last_sent || *estimate <= 0.9 * *last_sent;
}

std::vector<std::pair<std::string, Settings>> higher_qualities(const PipelineInfo& info,
                                                               const Settings& settings) {
  const std::vector<Quality>& qs = info.qualities;
  auto holds = [&](const Quality& q) {
    return !q.settings.empty() && std::all_of(q.settings.begin(), q.settings.end(), [&](auto& kv) {
      auto it = settings.find(kv.first);
      return it != settings.end() && it->second == kv.second;
    });
  };
  std::optional<size_t> at;
  for (size_t i = 0; i < qs.size(); ++i)
    if (holds(qs[i])) at = i;
  for (size_t i = 0; i < qs.size() && !at; ++i)
    if (qs[i].settings.empty()) at = i;  // the defaults
  if (!at) return {};
  Settings base = settings;
  for (const auto& kv : qs[*at].settings) base.erase(kv.first);
  std::vector<std::pair<std::string, Settings>> out;
  for (size_t j = *at + 1; j < qs.size(); ++j) {
    Settings s = base;
    for (const auto& [key, value] : qs[j].settings) s[key] = value;
    if (s != settings) out.emplace_back(qs[j].name, std::move(s));
  }
  return out;
}

int next_pass_spp(int spp, double trace_s, double other_s, double target_s) {
  double want = trace_s > 0 ? spp * (target_s - other_s) / trace_s : 4.0 * spp;
  return round_spp(std::clamp(want, spp / 2.0, spp * 4.0));
}

Refinement::Refinement(const Scene& scene, const std::string& pipeline, const std::string& terms,
                       const Settings& settings, RefineOptions options)
    : scene_(scene), pipeline_(pipeline), settings_(settings), options_(options), over_(false) {
  const PipelineInfo& info = pipeline_info(pipeline);
  terms_ = !terms.empty()             ? parse_terms(terms)
           : info.renders(Terms::All) ? Terms::All
                                      : info.terms.front();
  const std::string term_name = to_string(terms_);
  steps_.push_back({RefineStep::Stage::Full, pipeline, term_name, settings});
  if (const auto& c = options_.composite) {
    Scene small = scene_;  // the multiple term at the composite's size
    small.width = std::max(1, static_cast<int>(std::lround(scene_.width * c->scale)));
    small.height = std::max(1, static_cast<int>(std::lround(scene_.height * c->scale)));
    if (affordable(c->pipeline, small, Terms::Multiple, c->settings, options_)) {
      RefineStep m{RefineStep::Stage::Multiple, c->pipeline, to_string(Terms::Multiple),
                   c->settings};
      m.scale = c->scale;
      steps_.push_back(std::move(m));
      composite_error_ = composite_error(scene_, pipeline, settings, *c);
    }
  }
  // The reference's own Monte Carlo frames gain nothing from its presets (they set the marcher's
  // step); its marcher is exact up to its step: no passes follow it.
  const bool own = pipeline == "reference";
  const bool own_marches = own && terms_ == Terms::Single && !ReferenceSettings::read(settings).mc;
  if (!own || own_marches)
    for (auto& [name, s] : higher_qualities(info, settings))
      if (affordable(pipeline, scene_, terms_, s, options_))
        steps_.push_back({RefineStep::Stage::Quality, pipeline, term_name, s, name});
  if (terms_ == Terms::Surface || own_marches || options_.max_passes <= 0) return;
  // The reference of what the frames show: a composite's single plus multiple term is all (the
  // surface term of an index-matched medium is none).
  if (steps_.size() > 1 && steps_[1].stage == RefineStep::Stage::Multiple) {
    if (terms_ != Terms::Single) return;
    terms_ = Terms::All;
  }
  pass_settings_ = own ? settings : Settings{};
  if (terms_ == Terms::Single) pass_settings_["mc"] = 1;
  seed_ = own ? static_cast<int>(ReferenceSettings::read(settings).seed) : 1;
  Settings probe = pass_settings_;
  probe["spp"] = kMinPassSpp;
  RenderRequest r;
  r.terms = terms_;
  r.settings = probe;
  if (!affordable("reference", scene_, terms_, probe, options_)) return;
  double per_spp = estimate_cost("reference", scene_, r).seconds / kMinPassSpp;
  spp_ = round_spp(per_spp > 0 ? options_.pass_seconds / per_spp : kMaxPassSpp);
  reference_ = true;
}

std::optional<RefineStep> Refinement::next() const {
  if (over_) return std::nullopt;
  if (taken_ < steps_.size()) return steps_[taken_];
  return reference_pass();
}

std::optional<RefineStep> Refinement::reference_pass() const {
  if (!reference_ || pass_ >= options_.max_passes) return std::nullopt;
  RefineStep step{RefineStep::Stage::Reference, "reference", to_string(terms_), pass_settings_};
  step.pass = pass_ + 1;
  step.spp = spp_;
  step.settings["spp"] = spp_;
  step.settings["seed"] = (seed_ + step.pass) % (1 << 30);
  return step;
}

Refinement::Outcome Refinement::take(const RefineStep& step, RenderResult& result) {
  Outcome o;
  if (step.stage == RefineStep::Stage::Reference) {
    if (!result.std_error) {  // not a Monte Carlo estimate: nothing to accumulate
      over_ = true;
      o.state = State::Done;
      return o;
    }
    passes_.add(result.image, *result.std_error, step.spp);
    result.image = passes_.mean();
    result.std_error = passes_.std_error();
    result.error_estimate = relative_norm(*result.std_error, result.image);
    ++pass_;
    auto [trace, other] = pass_seconds(result);
    spp_ = next_pass_spp(step.spp, trace, other, options_.pass_seconds);
  } else {
    ++taken_;
    add_multiple(step, result);
  }
  o.estimate = result.error_estimate;
  if (o.estimate && *o.estimate <= options_.floor) {
    over_ = true;
    o.state = State::Converged;
  } else if (!next()) {
    over_ = true;
    o.state = State::Done;
  }
  // A reference pass is weighed against a frame without an estimate as if it had kAssumedError.
  std::optional<double> last = last_sent_;
  if (!last && step.stage == RefineStep::Stage::Reference) last = kAssumedError;
  const bool improves = !o.estimate || !last || *o.estimate < *last;
  o.send = step.stage == RefineStep::Stage::Full || worth_sending(o.estimate, last) ||
           (o.state != State::Converging && improves);
  // A frame without an estimate (a higher quality the table does not calibrate, with the same
  // multiple term added) leaves the last shown one as the mark later passes must beat: the page
  // never reads an error that rises.
  if (o.send && (o.estimate || !last_sent_)) last_sent_ = o.estimate;
  return o;
}

std::optional<double> composite_error(const Scene& scene, const std::string& pipeline,
                                      const Settings& settings, const Composite& composite) {
  auto quality_of = [](const std::string& name, const Settings& s) -> std::optional<std::string> {
    for (const Quality& q : pipeline_info(name).qualities)
      if (q.settings == s) return q.name;
    return std::nullopt;
  };
  auto single = quality_of(pipeline, settings);
  auto multiple = quality_of(composite.pipeline, composite.settings);
  if (!single || !multiple) return std::nullopt;
  auto p = CalibrationTable::shipped().predict_error(
      classify(scene, Terms::All),
      pipeline + ":" + *single + "+" + composite.pipeline + ":" + *multiple);
  if (!p) return std::nullopt;
  return p->value;
}

void Refinement::add_multiple(const RefineStep& step, RenderResult& result) {
  if (!options_.composite) return;
  if (step.stage == RefineStep::Stage::Full) {
    full_ = result.image;
    return;
  }
  if (step.stage == RefineStep::Stage::Multiple) {
    multiple_ = resample(result.image, full_.width, full_.height);
    result.image = full_;
    // The multiple term's own estimate is not the composite's: the calibrated one, if any.
    result.error_estimate = composite_error_;
  }
  if (!multiple_ || result.image.rgb.size() != multiple_->rgb.size()) return;
  for (size_t k = 0; k < result.image.rgb.size(); ++k) result.image.rgb[k] += multiple_->rgb[k];
}

nlohmann::json Refinement::describe(const RefineStep& step, State state) const {
  static const char* stages[] = {"full", "quality", "reference", "multiple"};
  nlohmann::json j = {{"stage", stages[static_cast<int>(step.stage)]},
                      {"state", to_string(state)},
                      {"floor", options_.floor}};
  if (step.stage == RefineStep::Stage::Quality) j["quality"] = step.quality;
  if (step.stage == RefineStep::Stage::Reference) {
    j["pass"] = step.pass;
    j["spp"] = passes_.samples();
  }
  if (step.stage == RefineStep::Stage::Multiple) {
    j["pipeline"] = step.pipeline;
    j["scale"] = step.scale;
  }
  return j;
}

std::string to_string(Refinement::State s) {
  switch (s) {
    case Refinement::State::Converging:
      return "converging";
    case Refinement::State::Converged:
      return "converged";
    case Refinement::State::Done:
      return "done";
  }
  return "done";
}

}  // namespace scatter::server
