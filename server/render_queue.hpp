// A thread that owns GPU contexts and the pipelines made on them. Network threads post jobs with a
// completion callback and never wait: each job runs on the thread, one at a time, in the order
// they came, and reports through its own callback (which posts to wherever its caller lives).
// The daemon keeps two: one for frames and renders, one for bakes, so that a bake never holds a
// live session's frame.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "gpu/gpu.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter::server {

// Thrown inside a job (from CancelToken::check) when it is cancelled or past its deadline.
struct JobCancelled : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Shared by a job and whoever may stop it: a vanished client, shutdown, or the deadline.
class CancelToken {
 public:
  // The first reason given wins; later calls change nothing.
  void cancel(const std::string& reason);
  // From now on check() throws once `seconds` have passed ("--max-render-s").
  void set_deadline(double seconds, std::string field);
  bool cancelled() const { return cancelled_; }
  // Throws JobCancelled (with the reason) when cancelled or past the deadline.
  void check() const;

 private:
  std::atomic<bool> cancelled_{false};
  mutable std::mutex mutex_;
  std::string reason_;
  std::optional<std::chrono::steady_clock::time_point> deadline_;
  double deadline_s_ = 0;
  std::string deadline_field_;
};

class RenderQueue {
 public:
  // What a job gets: the GPU and a cache of pipelines by name (made on first use).
  struct Context {
    gpu::Gpu gpu;
    BakeCache* cache = nullptr;  // shared by the pipelines that bake
    std::map<std::string, std::unique_ptr<Pipeline>> pipelines;
    Pipeline& pipeline(const std::string& name);
  };
  struct Job {
    // Runs on the queue's thread; must not throw (it reports its own outcome).
    std::function<void(Context&)> run;
    // Runs instead of `run` when the job is cancelled before it starts or the queue stops; gets
    // the reason. May run on the queue's thread or on the thread that calls stop().
    std::function<void(const std::string& why)> dropped;
    std::shared_ptr<CancelToken> cancel;  // optional
  };

  // `max_depth`: jobs that may wait at once; post() refuses more. `name` names the thread in logs.
  explicit RenderQueue(gpu::GpuOptions options, BakeCache* cache = nullptr, size_t max_depth = 64,
                       std::string name = "render");
  ~RenderQueue();  // stop(), then joins the thread (after the running job)
  RenderQueue(const RenderQueue&) = delete;
  RenderQueue& operator=(const RenderQueue&) = delete;

  // Queues `job`; false (and `job` dropped unrun, its `dropped` not called) when `max_depth` jobs
  // wait (unless `bypass_limit`: callers bounded by other means, live sessions with one frame
  // each) or the queue is stopping.
  bool post(Job job, bool bypass_limit = false);
  // Drops every waiting job (each `dropped` gets `why`), cancels the running one, and refuses
  // new jobs. Returns at once; wait_stopped() waits for the thread.
  void stop(const std::string& why);
  // After stop(): waits up to `timeout` for the running job to end; true when the thread is done.
  bool wait_stopped(std::chrono::milliseconds timeout);

  size_t depth() const;  // jobs waiting
  bool busy() const;     // a job is running
  size_t max_depth() const { return max_depth_; }
  BakeCache* cache() const { return cache_; }

 private:
  void run();

  // Made and destroyed on the queue's thread: GL objects must die where their context is current.
  gpu::GpuOptions options_;
  BakeCache* cache_;
  size_t max_depth_;
  std::string name_;
  std::unique_ptr<Context> context_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::deque<Job> jobs_;
  std::shared_ptr<CancelToken> running_;  // the running job's token, if it has one
  bool running_job_ = false, stopping_ = false, finished_ = false;
  std::thread thread_;
};

}  // namespace scatter::server
