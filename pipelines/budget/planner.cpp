#include "pipelines/budget/planner.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/errors.hpp"
#include "pipelines/auto_pipeline.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/lbl/lbl_limits.hpp"
#include "pipelines/registry.hpp"

namespace scatter {
namespace {

std::string percent(double e) {
  return short_number(100 * e) + " %";
}

std::string seconds(double s) {
  return short_number(s) + " s";
}

// A render's seconds, its bake's counted only when it is not made yet, and what a pipeline keeps
// between frames (lbl's volume, deposit and lattice) only when it does not hold it.
double part_seconds(const Scene& scene, const WayPart& part, const Settings& settings,
                    const IsBaked& baked, bool* needs_bake) {
  RenderRequest r{part.terms, settings, {}};
  const CostEstimate frame = estimate_cost(part.pipeline, scene, r, false);
  double s = frame.seconds;
  *needs_bake = pipeline_info(part.pipeline).bakes();
  if (!baked || !baked(part.pipeline, part.terms, settings)) return s;
  if (*needs_bake) {
    s -= estimate_cost(part.pipeline, scene, r, true).seconds;
    *needs_bake = false;
  } else {
    s -= frame.kept_seconds;
  }
  return std::max(0.0, s);
}

// The density contrast from which psf's multiple term is not offered (docs/BENCHMARKS.md, psf:
// layers of contrast 10 within 22.5 %, 15 and 30 at 27-28 %; the target is 25 %).
constexpr double kPsfMaxContrast = 12;

// lbl's multiple term is sent only media of g in its measured range (pipelines/lbl/lbl_limits.hpp).
constexpr double kLblMaxG = lbl::kMultipleMeasuredMaxG;
constexpr double kLblMinG = lbl::kMultipleMeasuredMinG;

// Why a way cannot render this scene at all, or empty.
std::string unfit(const Way& way, const SceneClass& c) {
  for (const WayPart& p : way.parts) {
    if (!pipeline_info(p.pipeline).renders(p.terms))
      return p.pipeline + " does not render the " + to_string(p.terms) + " term";
    if (p.pipeline == "thickness" && c.light_inside)
      return "thickness: a light inside the object's bounding sphere, which no shadow map sees";
    // psf's orders fly one mean free path for the whole medium (conserving each flight's
    // collisions): where thin parts carry light much further, its multiple term is off
    // (docs/BENCHMARKS.md: layers, contrast 10, 22.5 %; contrast 15, 27 %; the target is 25 %).
    if (p.pipeline == "psf" && p.terms != Terms::Single && c.contrast >= kPsfMaxContrast)
      return "psf: a density contrast of " + short_number(c.contrast) +
             " (largest over smallest), whose thin parts carry light further than psf's one mean "
             "free path";
    // Measured (docs/BENCHMARKS.md, lbl, issue 16, with the view's TMS reading): the sphere at
    // g 0.7 within 11 % on all terms, at g 0.9 9 %; nothing past g 0.9 is measured, and the
    // delta-Eddington lattice behind one exact scattering is further from a sharper forward
    // peak, whatever an extrapolated calibration says.
    if (p.pipeline == "lbl" && p.terms != Terms::Single && c.g > kLblMaxG)
      return "lbl: g " + short_number(c.g) + " above " + short_number(kLblMaxG) +
             ", past what its multiple term was measured at";
    if (p.pipeline == "lbl" && p.terms != Terms::Single && c.g < kLblMinG)
      return "lbl: g " + short_number(c.g) + " below " + short_number(kLblMinG) +
             ", where its multiple term is off by more than 10 % (measured 35 % at g -0.7: no "
             "forward peak for its delta-Eddington lattice to keep)";
  }
  return "";
}

}  // namespace

void check_budget(const std::string& pipeline, double max_error, const std::string& field) {
  if (!(max_error >= 1e-4 && max_error <= 1))
    throw ValidationError(
        field, "must be in [0.0001, 1] (a relative RMSE), got " + short_number(max_error));
  if (pipeline != "auto" && pipeline != "reference")
    throw ValidationError(field,
                          "is planned for by pipeline auto (and met by the reference's "
                          "sample count); pipeline " +
                              pipeline + " renders at its own settings");
}

BudgetChoice plan_budget(const Scene& scene, Terms terms, const Budget& budget,
                         const Settings& request, const CalibrationTable& table,
                         const IsBaked& baked) {
  const double max_error = budget.max_error;
  // The path tracer's samples are sized for the margin's aim with a fifth to spare for the
  // estimate's own scatter (1.2 (noise / aim)^2); the error expected at n samples of a count
  // sized so.
  const double aim = RenderRequest::kBudgetMargin * max_error;
  auto error_at = [&](double sized_spp, double n) {
    return aim * std::sqrt(sized_spp / n) / std::sqrt(1.2);
  };
  if (terms == Terms::Surface)
    throw ValidationError("terms", "the budget planner renders single, multiple or all terms");
  BudgetChoice best;
  best.cls = classify(scene, terms);
  best.expected_seconds = 1e300;
  std::vector<BudgetChoice> others;

  auto consider = [&](BudgetChoice c) {
    if (c.expected_seconds < best.expected_seconds) {
      if (best.expected_seconds < 1e300) others.push_back(std::move(best));
      best = std::move(c);
    } else {
      others.push_back(std::move(c));
    }
  };
  std::vector<PlanOption> rejected;  // unfit or not calibrated: never chosen
  std::vector<BudgetChoice> over;    // over budget: chosen only as a soft budget's fallback

  for (const std::string& id : table.ways(terms)) {
    Way way = Way::parse(id, terms);
    PlanOption o{id, {}, 0, 0, ""};
    if (std::string why = unfit(way, best.cls); !why.empty()) {
      o.note = "cannot: " + why;
      rejected.push_back(o);
      continue;
    }
    auto predicted = table.predict_error(best.cls, id);
    if (!predicted) {
      o.note = "not calibrated for " +
               std::string(best.cls.homogeneous ? "homogeneous" : "inhomogeneous") +
               (best.cls.index_matched ? ", index-matched" : ", dielectric") + " media";
      rejected.push_back(o);
      continue;
    }
    BudgetChoice c;
    c.way = way;
    c.cls = best.cls;
    c.expected_error = predicted->value;
    c.expected_seconds = 0;
    bool bakes = false;
    for (size_t i = 0; i < way.parts.size(); ++i) {
      Settings s = way.settings(i);
      for (const auto& [k, v] : AutoPipeline::settings_for(way.parts[i].pipeline, request))
        s[k] = v;
      bool needs_bake = false;
      c.expected_seconds += part_seconds(scene, way.parts[i], s, baked, &needs_bake);
      bakes = bakes || needs_bake;
      c.settings.push_back(std::move(s));
    }
    c.reason = id + ": expected " + percent(c.expected_error) + " (" + predicted->note + ") in " +
               seconds(c.expected_seconds) + (bakes ? " including its bake" : "");
    if (c.expected_error > max_error) {
      over.push_back(std::move(c));
      continue;
    }
    consider(std::move(c));
  }

  // The reference meets any budget.
  BudgetChoice ref;
  ref.cls = best.cls;
  double drawn_spp = 0;  // the sampled reference's expected samples (below)
  if (terms == Terms::Single) {
    // The single term's reference is the marcher at its finest quality.
    ref.way = Way::parse("reference:high", terms);
    ref.settings = {ref.way.settings(0)};
    for (const auto& [k, v] : AutoPipeline::settings_for("reference", request))
      ref.settings[0][k] = v;
    ref.expected_error = 0;
    bool unused = false;
    ref.expected_seconds = part_seconds(scene, ref.way.parts[0], ref.settings[0], baked, &unused);
    ref.reason = "reference:high: the single term's reference itself (the marcher), in " +
                 seconds(ref.expected_seconds);
  } else {
    // The path tracer for the multiple term; all terms add the marched single term to it.
    ref.way = terms == Terms::All ? Way::parse("reference:high+reference:sampled", terms)
                                  : Way{{{"reference", "sampled", terms}}};
    ref.sampled = true;
    auto noise = table.predict_noise(ref.cls);
    std::string how;
    if (noise) {
      // Relative standard error noise / sqrt(spp), sized for the aim (above); at run time the
      // path tracer samples until its standard error is under the aim.
      double spp = std::ceil(1.2 * std::pow(noise->value / aim, 2));
      ref.expected_spp = static_cast<int>(std::clamp(std::ceil(spp / 12) * 12, 24.0, 1048572.0));
      how = "noise " + short_number(noise->value) + "/sqrt(spp) (" + noise->note + ")";
    } else {
      ref.expected_spp = 256;
      how = "noise, not calibrated for this kind of medium (256 spp expected)";
    }
    Settings user = AutoPipeline::settings_for("reference", request);
    Settings s = user;
    s["spp"] = s.count("spp") ? std::min<double>(s["spp"], ref.expected_spp) : ref.expected_spp;
    if (terms == Terms::All) {
      Settings march = Way::parse("reference:high", Terms::Single).settings(0);
      for (const auto& [k, v] : user) march[k] = v;
      ref.settings.push_back(march);
    }
    ref.settings.push_back(s);
    ref.expected_error = max_error;
    ref.expected_seconds = 0;
    // The samples it is expected to draw: the path tracer goes on past spp, up to 8x (more only
    // where its measured standard error says the calibrated noise was low), until its standard
    // error is under the budget with its margin (pipelines/reference/reference_pipeline.cpp), so a
    // request's spp below the expected count is not what it costs.
    drawn_spp = std::min<double>(ref.expected_spp, 8 * s["spp"]);
    for (size_t i = 0; i < ref.way.parts.size(); ++i) {
      bool unused = false;
      Settings at = ref.settings[i];
      if (i + 1 == ref.way.parts.size()) {
        at["spp"] = drawn_spp;
        at.erase("max_seconds");  // the time the samples need (a max_seconds cuts them short)
      }
      ref.expected_seconds += part_seconds(scene, ref.way.parts[i], at, baked, &unused);
    }
    ref.reason = ref.way.id() + ": the path tracer" +
                 (terms == Terms::All ? " (plus the marched single term)" : "") +
                 ", sampled until its relative standard error is under " + percent(aim) +
                 " (the budget's " + percent(max_error) + " with its margin): about " +
                 std::to_string(ref.expected_spp) + " spp from its " + how + ", " +
                 seconds(ref.expected_seconds);
  }
  // The path tracer's seconds at `spp` samples without max_seconds, its other parts' seconds,
  // and its upload and seconds a sample.
  auto tracer_seconds = [&](const BudgetChoice& c, double spp) {
    Settings at = c.settings.back();
    at.erase("max_seconds");
    at["spp"] = spp;
    bool unused = false;
    return part_seconds(scene, c.way.parts.back(), at, baked, &unused);
  };
  auto before_seconds = [&](const BudgetChoice& c) {
    double before = 0;
    for (size_t i = 0; i + 1 < c.way.parts.size(); ++i) {
      bool unused = false;
      before += part_seconds(scene, c.way.parts[i], c.settings[i], baked, &unused);
    }
    return before;
  };
  struct Sampling {
    double upload, per_sample;
  };
  auto sampling = [&](const BudgetChoice& c) {
    const double at_3 = tracer_seconds(c, 3), per = (tracer_seconds(c, 99) - at_3) / 96;
    return Sampling{std::max(0.0, at_3 - 3 * per), per};
  };
  // The path tracer with as many samples as fit the soft budget's time: a fallback candidate.
  std::optional<BudgetChoice> capped;
  if (ref.sampled && budget.soft && ref.expected_seconds > budget.soft_seconds) {
    BudgetChoice c = ref;
    Settings& s = c.settings.back();
    double at_spp = ref.expected_seconds, spp = drawn_spp;
    const double at_12 = before_seconds(c) + tracer_seconds(c, 12);
    double per_sample = (at_spp - at_12) / std::max(1.0, spp - 12);
    double fit = per_sample > 0 ? 12 + (budget.soft_seconds - at_12) / per_sample : spp;
    int n = static_cast<int>(std::floor(fit / 12) * 12);
    if (n >= 12 && ref.expected_spp > 0) {
      s["spp"] = n;
      c.sampled = false;  // exactly n samples: no budget to sample towards
      c.expected_spp = n;
      c.expected_error = error_at(ref.expected_spp, n);
      c.expected_seconds = budget.soft_seconds;
      c.reason = c.way.id() + ": the path tracer at " + std::to_string(n) + " spp, what fits " +
                 seconds(budget.soft_seconds) + ": expected " + percent(c.expected_error);
      capped = std::move(c);
    }
  }
  // A soft budget's path tracer stops sampling at its time, whatever its estimate said (the
  // estimate can be several times low: docs/STRESS.md, mixed/1680): the soft seconds less its
  // other parts' and its own upload (at least a quarter of them), or the request's own
  // max_seconds if less.
  const int needed_spp = ref.expected_spp;
  const bool tracer = ref.sampled;  // ref is moved into the choice below
  if (budget.soft && tracer) {
    for (BudgetChoice* c : {&ref, capped ? &*capped : nullptr}) {
      if (!c) continue;
      double left = std::max(budget.soft_seconds - before_seconds(*c) - sampling(*c).upload,
                             budget.soft_seconds / 4);
      Settings& s = c->settings.back();
      if (s.count("max_seconds") && s["max_seconds"] > 0) left = std::min(left, s["max_seconds"]);
      s["max_seconds"] = left;
      c->reason += "; its samples stop at " + seconds(left) + " (max_seconds)";
    }
  }
  consider(std::move(ref));

  // A soft budget (none was asked for) does not wait for the reference: past soft_seconds, the
  // most accurate way expected within them.
  if (budget.soft && best.expected_seconds > budget.soft_seconds) {
    std::vector<BudgetChoice*> quick;
    for (auto* list : {&others, &over})
      for (BudgetChoice& c : *list)
        if (c.expected_seconds <= budget.soft_seconds) quick.push_back(&c);
    if (capped) quick.push_back(&*capped);
    if (!quick.empty()) {
      BudgetChoice* pick = *std::min_element(quick.begin(), quick.end(),
                                             [](const BudgetChoice* a, const BudgetChoice* b) {
                                               return a->expected_error < b->expected_error;
                                             });
      BudgetChoice chosen = std::move(*pick);
      if (capped && pick == &*capped) {
        capped.reset();
      } else {
        for (auto* list : {&others, &over})
          list->erase(std::remove_if(list->begin(), list->end(),
                                     [](const BudgetChoice& c) { return c.way.parts.empty(); }),
                      list->end());
      }
      others.push_back(std::move(best));
      best = std::move(chosen);
      best.reason = "nothing meets it within " + seconds(budget.soft_seconds) +
                    "; the most accurate way expected within them: " + best.reason;
    }
  }
  if (capped) others.push_back(std::move(*capped));
  // A path tracer whose max_seconds cuts its samples short (none quicker was found): the
  // samples expected to fit, their error and time.
  if (budget.soft && tracer && !best.way.parts.empty() && !best.settings.empty() &&
      best.way.parts.back().pipeline == "reference" && best.settings.back().count("max_seconds") &&
      needed_spp > 0) {
    const Sampling at = sampling(best);
    const double per = at.per_sample, left = best.settings.back().at("max_seconds");
    const double planned = best.sampled ? drawn_spp : best.expected_spp;
    const double fit = per > 0 ? std::max(3.0, std::floor(left / per)) : planned;
    if (fit < planned) {
      best.expected_error = error_at(needed_spp, fit);
      best.expected_seconds = before_seconds(best) + at.upload + left;
      best.reason += ": about " + std::to_string(int(fit)) + " samples fit, expected " +
                     percent(best.expected_error) + " in " + seconds(best.expected_seconds);
    }
  }

  for (const BudgetChoice& c : others)
    best.alternatives.push_back({c.way.id(), c.settings.size() == 1 ? c.settings[0] : Settings{},
                                 c.expected_error, c.expected_seconds, "slower: " + c.reason});
  for (const BudgetChoice& c : over)
    best.alternatives.push_back({c.way.id(), c.settings.size() == 1 ? c.settings[0] : Settings{},
                                 c.expected_error, c.expected_seconds, "over budget: " + c.reason});
  for (PlanOption& o : rejected) best.alternatives.push_back(std::move(o));
  best.reason = "budget " + percent(max_error) +
                (budget.soft ? " (the default; quality.max_error sets one)" : "") + ", " +
                describe(best.cls) + ": " + best.reason;
  return best;
}

}  // namespace scatter
