// The one thread that owns the GPU contexts and the pipelines. Network threads hand it jobs and
// wait on futures; jobs run one at a time, in the order they came.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "gpu/gpu.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter::server {

class RenderQueue {
 public:
  // What a job gets: the GPU and a cache of pipelines by name (made on first use).
  struct Context {
    gpu::Gpu gpu;
    BakeCache* cache = nullptr;  // shared by the pipelines that bake
    std::map<std::string, std::unique_ptr<Pipeline>> pipelines;
    Pipeline& pipeline(const std::string& name);
  };

  explicit RenderQueue(gpu::GpuOptions options, BakeCache* cache = nullptr);
  ~RenderQueue();  // finishes the running job, drops the rest, joins the thread
  RenderQueue(const RenderQueue&) = delete;
  RenderQueue& operator=(const RenderQueue&) = delete;

  // Runs `job` on the render thread with its Gpu and pipeline cache; the future carries the
  // result or the job's exception.
  template <class F>
  auto submit(F job) -> std::future<decltype(job(std::declval<Context&>()))>;

  size_t depth() const;
  BakeCache* cache() const { return cache_; }

 private:
  void run();

  // Made and destroyed on the render thread: GL objects must die where their context is current.
  gpu::GpuOptions options_;
  BakeCache* cache_;
  std::unique_ptr<Context> context_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::thread thread_;
};

template <class F>
auto RenderQueue::submit(F job) -> std::future<decltype(job(std::declval<Context&>()))> {
  using R = decltype(job(std::declval<Context&>()));
  auto task = std::make_shared<std::packaged_task<R()>>([this, job = std::move(job)]() mutable {
    return job(*context_);
  });
  auto future = task->get_future();
  {
    std::lock_guard lock(mutex_);
    jobs_.emplace_back([task] { (*task)(); });
  }
  wake_.notify_one();
  return future;
}

}  // namespace scatter::server
