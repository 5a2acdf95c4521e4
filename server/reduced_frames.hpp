// The reduced frames of a live session while the user drags (server/ws_session.hpp): per pipeline,
// the fraction of each side they render at and whether the pipeline's draft frame settings are
// used, steered by their measured render times against a frame-time budget. Apart from the
// session so that it can be tested without sockets or a GPU.
#pragma once

#include <map>
#include <string>

#include "pipelines/pipeline.hpp"

namespace scatter::server {

class ReducedFrames {
 public:
  // What a reduced frame aims to take, render only, in milliseconds.
  static constexpr double kFrameBudgetMs = 80;
  static constexpr double kMinScale = 0.25, kMaxScale = 0.5, kStartScale = 0.5;

  struct Choice {
    double scale = kStartScale;  // of each side
    bool draft = false;          // the draft quality's frame-only settings
  };
  // The next reduced frame of `pipeline`.
  const Choice& choice(const std::string& pipeline) { return chosen_[pipeline]; }
  // `settings` with the pipeline's draft frame-only settings where chosen.
  Settings settings(const std::string& pipeline, const Settings& settings);
  // Steers the pipeline's next reduced frames from one that took `render_ms`: the side scale
  // follows sqrt(budget / measured) (pixels cost about linearly), between kMinScale and
  // kMaxScale; at kMinScale and still over budget, the draft frame settings too.
  void measured(const std::string& pipeline, double render_ms);

 private:
  std::map<std::string, Choice> chosen_;
};

// `s` with the pipeline's settings for moving frames (PipelineInfo::moving, else its draft
// quality's) that shape only the frame (none that would make another bake product or reset a kept
// state): cheaper frames while the user drags.
Settings with_draft(const std::string& pipeline, Settings s);

}  // namespace scatter::server
