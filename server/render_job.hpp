// One render on the render thread, as POST /api/render and live sessions ask for it: the shared
// scene with this frame's camera, lights and size, a cancel token, and a completion callback
// that runs on the render thread (callers post from it to their own executors).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "server/metrics.hpp"
#include "server/render_queue.hpp"

namespace scatter::server {

struct FrameSpec {
  std::shared_ptr<const Scene> scene;  // shared, never copied for a frame
  std::optional<Camera> camera;        // overrides, when set
  std::optional<std::vector<Light>> lights;
  int width = 0, height = 0;             // 0: the scene's
  std::string pipeline = "auto", terms;  // terms empty: all, if the pipeline has it, else its first
  Settings settings;
  std::optional<double> max_error;  // the RenderRequest's
  double scene_load_ms = 0;         // reported as a "scene_load" stage when > 0
  double max_seconds = 0;           // > 0: cancelled once it has run this long (--max-render-s)
};

// A request estimated to cost more than the server allows (413); names the field to change.
struct RequestTooCostly : ValidationError {
  using ValidationError::ValidationError;
};

// A request the server cannot answer for a reason of its own (503): a shipped scene whose mesh
// file is missing, an assets folder it cannot write; names the field that led there.
struct ServerUnavailable : ValidationError {
  using ValidationError::ValidationError;
};

struct RenderOutcome {
  std::optional<RenderResult> result;
  int status = 200;  // else 400 (a ValidationError), 503 (cancelled, GPU unavailable), 500
  std::string error, field;
  double wait_ms = 0;  // queued behind other jobs
};

// Queues the render; `done` runs exactly once, on the render thread (or on the thread that stops
// the queue). Returns false, calling nothing, when the queue is full (see RenderQueue::post) or
// stopping.
bool post_render(RenderQueue& queue, Metrics& metrics, FrameSpec spec,
                 std::shared_ptr<CancelToken> cancel, std::function<void(RenderOutcome)> done,
                 bool bypass_limit = false);

}  // namespace scatter::server
