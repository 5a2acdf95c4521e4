#include "server/render_queue.hpp"

#include <spdlog/spdlog.h>

#include "pipelines/pipeline.hpp"

namespace scatter::server {

void CancelToken::cancel(const std::string& reason) {
  std::lock_guard lock(mutex_);
  if (cancelled_) return;
  reason_ = reason;
  cancelled_ = true;
}

void CancelToken::set_deadline(double seconds, std::string field) {
  std::lock_guard lock(mutex_);
  deadline_ = std::chrono::steady_clock::now() +
              std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                  std::chrono::duration<double>(seconds));
  deadline_s_ = seconds;
  deadline_field_ = std::move(field);
}

void CancelToken::check() const {
  std::lock_guard lock(mutex_);
  if (cancelled_) throw JobCancelled(reason_);
  if (deadline_ && std::chrono::steady_clock::now() > *deadline_)
    throw JobCancelled("stopped after " + short_number(deadline_s_) + " s, the server's limit (" +
                       deadline_field_ + ")");
}

RenderQueue::RenderQueue(gpu::GpuOptions options, BakeCache* cache, size_t max_depth,
                         std::string name)
    : options_(std::move(options)),
      cache_(cache),
      max_depth_(max_depth),
      name_(std::move(name)),
      thread_([this] { run(); }) {}

RenderQueue::~RenderQueue() {
  stop("the server is stopping");
  thread_.join();
}

bool RenderQueue::post(Job job, bool bypass_limit) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || (!bypass_limit && jobs_.size() >= max_depth_)) return false;
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
  return true;
}

void RenderQueue::stop(const std::string& why) {
  std::deque<Job> dropped;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    dropped.swap(jobs_);
    if (running_) running_->cancel(why);
  }
  wake_.notify_one();
  for (auto& job : dropped)
    if (job.dropped) job.dropped(why);
}

bool RenderQueue::wait_stopped(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return done_.wait_for(lock, timeout, [&] { return finished_; });
}

size_t RenderQueue::depth() const {
  std::lock_guard lock(mutex_);
  return jobs_.size();
}

bool RenderQueue::busy() const {
  std::lock_guard lock(mutex_);
  return running_job_;
}

Pipeline& RenderQueue::Context::pipeline(const std::string& name) {
  auto& p = pipelines[name];
  if (!p) p = make_pipeline(name, gpu, cache);
  return *p;
}

void RenderQueue::run() {
  context_ = std::make_unique<Context>(Context{gpu::Gpu(options_), cache_, {}});
  for (;;) {
    Job job;
    {
      std::unique_lock lock(mutex_);
      running_job_ = false;
      running_.reset();
      wake_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (stopping_) break;
      job = std::move(jobs_.front());
      jobs_.pop_front();
      if (job.cancel && job.cancel->cancelled()) {
        lock.unlock();
        try {
          job.cancel->check();
        } catch (const JobCancelled& e) {
          if (job.dropped) job.dropped(e.what());
        }
        continue;
      }
      running_ = job.cancel;
      running_job_ = true;
    }
    try {
      job.run(*context_);
    } catch (const std::exception& e) {  // a job should report its own errors; never die of one
      spdlog::error("event=job_error queue={} error=\"{}\"", name_, e.what());
    }
  }
  context_->pipelines.clear();  // before the contexts they belong to
  context_.reset();
  std::lock_guard lock(mutex_);
  finished_ = true;
  done_.notify_all();
}

}  // namespace scatter::server
