// The budget planner: the fastest way to render a scene's terms within an error budget
// (relative RMSE against the reference), from the scene's class and the calibration table.
//
// Candidates are the ways the table calibrated for the terms (pipelines/budget/calibration.hpp),
// each with its predicted error (conservative: the worse of the two nearest calibration scenes of
// the same kind, doubled outside their range) and its time (the cost estimate of its parts,
// pipelines/cost.hpp, with a bake counted unless it is already in the cache), and the reference,
// which meets any budget: the marcher for the single term (the single term's reference itself),
// the path tracer for the others with the samples its calibrated noise says the budget needs (at
// run time it samples until its own standard error says so). The fastest candidate expected to
// meet the budget wins; the plan lists the others and why they lost.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "pipelines/budget/calibration.hpp"
#include "pipelines/budget/scene_class.hpp"

namespace scatter {

// The budget auto plans by when a request names none.
constexpr double kDefaultMaxError = 0.10;

struct Budget {
  double max_error = kDefaultMaxError;
  // A soft budget (the default, none asked for) does not wait for the reference: when only a
  // render past soft_seconds meets it, the most accurate way expected within them is chosen
  // (the path tracer with the samples that fit among them).
  bool soft = false;
  double soft_seconds = 30;
};

struct BudgetChoice {
  // For the path tracer: "reference:sampled" (multiple), "reference:high+reference:sampled" (all)
  Way way;
  std::vector<Settings> settings;  // per part: the quality's settings, the request's over them
  double expected_error = 0, expected_seconds = 0;
  // The path tracer (the way's last part), sampling until its standard error is under the budget
  // with its margin (RenderRequest::kBudgetMargin).
  bool sampled = false;
  int expected_spp = 0;  // sampled: what the calibrated noise says the budget needs
  SceneClass cls;
  std::string reason;  // the plan's "choose" stage
  std::vector<PlanOption> alternatives;
};

// Whether what a pipeline makes before a frame of these terms and settings is already made: the
// bake a pipeline that bakes needs (in the cache), or the state one that keeps state holds
// (Pipeline::keeps: lbl's volume, deposit and lattice). Null: count everything.
using IsBaked =
    std::function<bool(const std::string& pipeline, Terms terms, const Settings& settings)>;

// Throws ValidationError (naming `field`) unless max_error is in [1e-4, 1] and `pipeline` takes a
// budget: auto plans by it, the reference samples until it is met; the others render at their
// settings.
void check_budget(const std::string& pipeline, double max_error, const std::string& field);

BudgetChoice plan_budget(const Scene& scene, Terms terms, const Budget& budget,
                         const Settings& request, const CalibrationTable& table,
                         const IsBaked& baked = nullptr);

}  // namespace scatter
