#include "server/render_queue.hpp"

namespace scatter::server {

RenderQueue::RenderQueue(gpu::GpuOptions options, BakeCache* cache)
    : options_(std::move(options)), cache_(cache), thread_([this] { run(); }) {}

RenderQueue::~RenderQueue() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    jobs_.clear();  // their futures report broken_promise
  }
  wake_.notify_one();
  thread_.join();
}

size_t RenderQueue::depth() const {
  std::lock_guard lock(mutex_);
  return jobs_.size();
}

Pipeline& RenderQueue::Context::pipeline(const std::string& name) {
  auto& p = pipelines[name];
  if (!p) p = make_pipeline(name, gpu, cache);
  return *p;
}

void RenderQueue::run() {
  context_ = std::make_unique<Context>(Context{gpu::Gpu(options_), cache_, {}});
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (stopping_) {
        lock.unlock();
        context_->pipelines.clear();  // before the contexts they belong to
        context_.reset();
        return;
      }
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    job();  // packaged_task stores any exception in the future
  }
}

}  // namespace scatter::server
