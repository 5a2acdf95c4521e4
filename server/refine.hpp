// What a still live view renders once camera and lights stop (docs/API.md, "Refinement"), apart
// from the network code so that it can be tested without sockets or a GPU:
//
//   1. full      the full-size frame of the session's pipeline and settings (always sent)
//   2. multiple  with a composite (RefineOptions::composite): the multiple-scattering term from
//                another pipeline (psf, lbl), rendered at a fraction of the size (the term is
//                smooth), resampled and added to the full frame; later quality frames get it too
//   3. quality   the pipeline's higher qualities (its registry's `qualities` after the one the
//                session's settings are at), each preset's settings over the session's
//   4. reference progressive passes of the reference's Monte Carlo estimator of the session's
//                terms (single: "mc": 1; not for the surface term; a composite of the single
//                term: all), a new seed each pass, accumulated (pipelines/accumulate.hpp); each
//                pass sized to take ~pass_seconds
//
// Each result carries an estimated error (RenderResult::error_estimate: the path tracer's from its
// standard error, the approximations' from calibration where known). A result is sent only when
// its estimate is at most 0.9 x the last estimate sent (a frame sent without one, such as a
// higher quality's, does not reset it); refinement ends at the floor, after
// max_passes reference passes, or when the session starts a new one (the user moved).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipelines/accumulate.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/registry.hpp"

namespace scatter::server {

// The multiple-scattering term a still frame of a single-term pipeline adds (a session's hello's
// "composite"): from `pipeline` (one that renders the multiple term) with `settings`, at `scale`
// of each side.
struct Composite {
  std::string pipeline;
  Settings settings;
  double scale = 0.5;
};

// A composite frame's calibrated error (pipelines/budget/calibration.json): the way
// "pipeline:Q+composite:Q'" where both settings are one of their pipeline's qualities and the
// table calibrated it for the scene's class; none otherwise.
std::optional<double> composite_error(const Scene& scene, const std::string& pipeline,
                                      const Settings& settings, const Composite& composite);

struct RefineOptions {
  double floor = 0.01;        // stop once the estimated error is at or under this
  int max_passes = 64;        // reference passes, at most
  double pass_seconds = 1.0;  // what one reference pass aims to take
  // Steps estimated past these are left out (--max-render-s, --max-request-mb; 0: no limit).
  double max_render_s = 0, max_request_mb = 0;
  // And steps estimated past this (0: no limit): a refinement job holds the render thread, which
  // the other sessions share, so each stays short (a live session passes 10 x pass_seconds).
  double step_max_s = 0;
  std::optional<Composite> composite;  // the multiple term to add, if any
};

// One render of the refinement.
struct RefineStep {
  enum class Stage { Full, Quality, Reference, Multiple };
  Stage stage = Stage::Full;
  std::string pipeline, terms;
  Settings settings;
  std::string quality;  // Quality: the preset's name
  int pass = 0;         // Reference: 1, 2, ...
  int spp = 0;          // Reference: this pass's samples per pixel
  double scale = 1;     // of each side of the scene's image (Multiple: the composite's)
};

// A refined frame is worth sending when its estimate is at most 0.9 x the last sent frame's; one
// without an estimate, or after a frame without one, is sent (nothing says it is worse).
bool worth_sending(std::optional<double> estimate, std::optional<double> last_sent);

// The qualities of `info` above the one `settings` are at (the last preset whose non-empty
// settings all hold in `settings`; else the pipeline's defaults, "normal"), in order, each as
// (name, settings to render): `settings` without the current preset's keys, the higher one's
// over them.
std::vector<std::pair<std::string, Settings>> higher_qualities(const PipelineInfo& info,
                                                               const Settings& settings);

// Samples per pixel of the next reference pass, given that the last (`spp`) took `trace_s` to
// sample and `other_s` for the rest (voxelize, upload): aimed at `target_s` in all, at most 4x
// more or 2x fewer, a multiple of 3 (one colour channel a sample) in [kMinPassSpp, kMaxPassSpp].
// At least 4 samples a channel: a pass's standard error comes from its sample variance.
constexpr int kMinPassSpp = 12, kMaxPassSpp = 3 << 11;
int next_pass_spp(int spp, double trace_s, double other_s, double target_s);

class Refinement {
 public:
  enum class State { Converging, Converged, Done };
  struct Outcome {
    bool send = false;
    State state = State::Converging;
    std::optional<double> estimate;
  };

  Refinement() = default;  // nothing to refine: over at once
  // A still view of `scene` (the full size, this view's camera and lights) by `pipeline` with
  // `terms` (empty: all if the pipeline renders it, else its first) and `settings`.
  Refinement(const Scene& scene, const std::string& pipeline, const std::string& terms,
             const Settings& settings, RefineOptions options);

  // The render after those taken so far (the first is the full frame); empty once over.
  std::optional<RefineStep> next() const;
  // Takes the result of next(). A reference pass is accumulated: `result`'s image, std_error and
  // error_estimate become the accumulation's. A multiple-term step's image becomes the full
  // frame's plus it (resampled to the full size), and so do later quality frames'. Says whether
  // to send it: the full frame always; a later one when worth_sending(), or when it ends the
  // refinement and improves on the last sent.
  Outcome take(const RefineStep& step, RenderResult& result);
  void stop() { over_ = true; }  // a step failed
  bool over() const { return !next(); }
  std::optional<double> last_sent() const { return last_sent_; }
  long long reference_samples() const { return passes_.samples(); }
  // A frame header's "refine": {"stage", "state", "floor", and "quality", "pass" and "spp", or
  // "pipeline" and "scale" (multiple)}.
  nlohmann::json describe(const RefineStep& step, State state) const;

 private:
  std::optional<RefineStep> reference_pass() const;
  // With a composite: keeps the full frame, and adds the multiple term to `result`'s image.
  void add_multiple(const RefineStep& step, RenderResult& result);

  Scene scene_;
  std::string pipeline_;
  Terms terms_ = Terms::All;
  Settings settings_;
  RefineOptions options_;
  std::vector<RefineStep> steps_;          // full, the multiple term, then the qualities
  std::optional<double> composite_error_;  // the composite frames' calibrated error
  Image full_;                     // with a composite: the full frame, and the multiple term
  std::optional<Image> multiple_;  // resampled to its size, once rendered
  size_t taken_ = 0;               // of steps_
  bool reference_ = false;         // reference passes follow
  Settings pass_settings_;         // the reference's, but spp and seed
  int seed_ = 1, spp_ = 3, pass_ = 0;
  PassAccumulator passes_;
  std::optional<double> last_sent_;
  bool over_ = true;
};

std::string to_string(Refinement::State s);

}  // namespace scatter::server
