// Bake jobs: the records behind POST/GET/DELETE /api/bakes. A job is named by what it bakes (its
// id is derived from the asset, pipeline and settings), so asking twice for the same bake finds the
// same job, or, after a restart, a new one that the content-addressed cache answers at once.
// The work itself runs wherever the caller sends it (the daemon: its render thread); the job only
// keeps state, progress and the result, and turns a cancel request into a BakeCancelled thrown from
// the next progress report.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bake/bake_result.hpp"

namespace scatter {

struct BakeCancelled : std::runtime_error {
  BakeCancelled() : std::runtime_error("bake cancelled") {}
};

class BakeJob {
 public:
  enum class State { Queued, Running, Done, Failed, Cancelled };

  BakeJob(std::string id, std::string pipeline,
          std::vector<std::pair<std::string, double>> stage_weights);

  const std::string& id() const { return id_; }
  // Runs `work` with a progress callback (which throws BakeCancelled once cancel() was asked),
  // recording the outcome. A job cancelled while queued does not run `work`.
  void run(const std::function<BakeResult(const BakeProgress&)>& work);
  // Queued or running: marks it; returns false if it had already finished.
  bool cancel();
  State state() const;
  bool finished() const;
  bool cancel_requested() const { return cancel_; }
  uint64_t serial() const { return serial_; }  // creation order
  nlohmann::json status() const;  // id, state, pipeline, stage, progress, timings, error, ...

 private:
  void report(const std::string& stage, double fraction);

  const std::string id_, pipeline_;
  const std::vector<std::pair<std::string, double>> weights_;  // stage -> share of the whole
  const std::chrono::steady_clock::time_point created_ = std::chrono::steady_clock::now();
  mutable std::mutex mutex_;
  std::atomic<bool> cancel_{false};
  State state_ = State::Queued;
  std::string stage_ = "queued", error_;
  double progress_ = 0;
  std::optional<BakeResult> result_;
  double seconds_ = 0;
  uint64_t serial_ = 0;
};

std::string to_string(BakeJob::State s);

class BakeJobs {
 public:
  static constexpr int kMaxActive = 8;     // queued or running at once; more: Busy
  static constexpr size_t kMaxKept = 256;  // job records kept; the oldest finished go first
  struct Busy : std::runtime_error {
    Busy() : std::runtime_error("too many bakes queued or running; try again when one finishes") {}
  };

  // The job for `identity` (what is baked: asset, pipeline, settings): the existing one unless it
  // failed or was cancelled (or is being cancelled), else a new one, which `start` must arrange to
  // run. `created` says which. Throws Busy when kMaxActive jobs are queued or running.
  std::shared_ptr<BakeJob> submit(const std::string& identity, const std::string& pipeline,
                                  std::vector<std::pair<std::string, double>> stage_weights,
                                  const std::function<void(std::shared_ptr<BakeJob>)>& start,
                                  bool* created);
  std::shared_ptr<BakeJob> find(const std::string& id) const;
  std::vector<std::shared_ptr<BakeJob>> list() const;
  // Jobs in each state, for metrics.
  std::map<std::string, int> counts() const;

  // The job id for an identity: a product's bake key is its own id (the job is named by what it
  // makes); any other text gets 16 hex digits of its SHA-256.
  static std::string id_for(const std::string& identity);

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<BakeJob>> jobs_;
};

}  // namespace scatter
