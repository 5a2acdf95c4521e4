#include "bake/jobs.hpp"

#include <algorithm>

#include "bake/cache.hpp"

namespace scatter {

std::string to_string(BakeJob::State s) {
  switch (s) {
    case BakeJob::State::Queued:
      return "queued";
    case BakeJob::State::Running:
      return "running";
    case BakeJob::State::Done:
      return "done";
    case BakeJob::State::Failed:
      return "failed";
    case BakeJob::State::Cancelled:
      return "cancelled";
  }
  return "unknown";
}

BakeJob::BakeJob(std::string id, std::string pipeline,
                 std::vector<std::pair<std::string, double>> stage_weights)
    : id_(std::move(id)), pipeline_(std::move(pipeline)), weights_(std::move(stage_weights)) {
  static std::atomic<uint64_t> next{0};
  serial_ = next++;
}

void BakeJob::report(const std::string& stage, double fraction) {
  if (cancel_) throw BakeCancelled();
  std::lock_guard lock(mutex_);
  stage_ = stage;
  // Overall progress: the shares of the stages before this one plus this one's share done.
  double before = 0, share = 0;
  bool found = false;
  for (const auto& [name, w] : weights_) {
    if (name == stage) {
      share = w;
      found = true;
      break;
    }
    before += w;
  }
  if (found)
    progress_ = std::max(progress_, std::min(1.0, before + share * std::clamp(fraction, 0.0, 1.0)));
}

void BakeJob::run(const std::function<BakeResult(const BakeProgress&)>& work) {
  {
    std::lock_guard lock(mutex_);
    if (cancel_) {
      state_ = State::Cancelled;
      stage_ = "cancelled";
      return;
    }
    state_ = State::Running;
    stage_ = "starting";
  }
  auto start = std::chrono::steady_clock::now();
  State end = State::Done;
  std::string error;
  std::optional<BakeResult> result;
  try {
    result = work([this](const std::string& stage, double f) { report(stage, f); });
  } catch (const BakeCancelled&) {
    end = State::Cancelled;
  } catch (const std::exception& e) {
    end = State::Failed;
    error = e.what();
  }
  std::lock_guard lock(mutex_);
  seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  state_ = end;
  error_ = error;
  result_ = std::move(result);
  stage_ = to_string(end);
  if (end == State::Done) progress_ = 1;
}

bool BakeJob::cancel() {
  std::lock_guard lock(mutex_);
  if (state_ != State::Queued && state_ != State::Running) return false;
  cancel_ = true;
  if (state_ == State::Queued) {  // it will not start: say so now
    state_ = State::Cancelled;
    stage_ = "cancelled";
  }
  return true;
}

BakeJob::State BakeJob::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

bool BakeJob::finished() const {
  State s = state();
  return s == State::Done || s == State::Failed || s == State::Cancelled;
}

nlohmann::json BakeJob::status() const {
  std::lock_guard lock(mutex_);
  nlohmann::json j = {
      {"id", id_},
      {"pipeline", pipeline_},
      {"state", to_string(state_)},
      {"stage", stage_},
      {"progress", progress_},
      {"cancel_requested", cancel_.load()},
      {"age_s",
       std::chrono::duration<double>(std::chrono::steady_clock::now() - created_).count()}};
  if (!error_.empty()) j["error"] = error_;
  if (result_) {
    j["needed"] = result_->needed;
    j["cache_hit"] = result_->cache_hit;
    j["seconds"] = seconds_;
    if (result_->needed) {
      j["key"] = result_->key;
      nlohmann::json t = nlohmann::json::object(), b = nlohmann::json::object();
      for (const auto& s : result_->timings) t[s.stage] = s.ms;
      for (const auto& s : result_->bake_timings) b[s.stage] = s.ms;
      j["timings_ms"] = t;
      j["bake_timings_ms"] = b;
      j["stats"] = result_->stats;
    }
  }
  return j;
}

std::string BakeJobs::id_for(const std::string& identity) {
  return is_bake_key(identity) ? identity : sha256_hex(identity).substr(0, 16);
}

std::shared_ptr<BakeJob> BakeJobs::submit(
    const std::string& identity, const std::string& pipeline,
    std::vector<std::pair<std::string, double>> stage_weights,
    const std::function<void(std::shared_ptr<BakeJob>)>& start, bool* created) {
  std::string id = id_for(identity);
  std::shared_ptr<BakeJob> job;
  {
    std::lock_guard lock(mutex_);
    auto& slot = jobs_[id];
    // A job that failed, was cancelled or is being cancelled is replaced: asking again means again.
    if (slot && !slot->cancel_requested() && slot->state() != BakeJob::State::Failed &&
        slot->state() != BakeJob::State::Cancelled) {
      if (created) *created = false;
      return slot;
    }
    int active = 0;
    for (const auto& [other, j] : jobs_)
      if (j && j != slot && !j->finished()) ++active;
    if (active >= kMaxActive) {
      if (!slot) jobs_.erase(id);
      throw Busy();
    }
    slot = std::make_shared<BakeJob>(id, pipeline, std::move(stage_weights));
    job = slot;
    // Forget the oldest finished jobs beyond kMaxKept (their products stay in the cache).
    while (jobs_.size() > kMaxKept) {
      auto oldest = jobs_.end();
      for (auto it = jobs_.begin(); it != jobs_.end(); ++it)
        if (it->second->finished() &&
            (oldest == jobs_.end() || it->second->serial() < oldest->second->serial()))
          oldest = it;
      if (oldest == jobs_.end()) break;
      jobs_.erase(oldest);
    }
  }
  if (created) *created = true;
  start(job);
  return job;
}

std::shared_ptr<BakeJob> BakeJobs::find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<BakeJob>> BakeJobs::list() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<BakeJob>> out;
  for (const auto& [id, job] : jobs_) out.push_back(job);
  return out;
}

std::map<std::string, int> BakeJobs::counts() const {
  std::map<std::string, int> c;
  for (const auto& j : list()) c[to_string(j->state())]++;
  return c;
}

}  // namespace scatter
