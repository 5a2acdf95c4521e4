// Bake job records: progress from stage shares, cancel before and during a run, replacement of
// failed and cancelled jobs, the limit on active jobs, and forgetting old finished ones.
#include "bake/jobs.hpp"

#include <gtest/gtest.h>

namespace scatter {
namespace {

std::string numbered(std::string prefix, size_t i) {
  prefix += std::to_string(i);
  return prefix;
}

const std::vector<std::pair<std::string, double>> kStages = {{"a", 0.25}, {"b", 0.75}};

std::shared_ptr<BakeJob> submit(BakeJobs& jobs, const std::string& identity,
                                bool* created = nullptr) {
  return jobs.submit(
      identity, "single", kStages, [](std::shared_ptr<BakeJob>) {}, created);
}

TEST(BakeJobs, ProgressFollowsStageSharesAndNeverDecreases) {
  BakeJobs jobs;
  auto job = submit(jobs, "x");
  std::vector<double> seen;
  job->run([&](const BakeProgress& progress) {
    progress("a", 0.0);
    seen.push_back(job->status()["progress"]);
    progress("a", 1.0);
    seen.push_back(job->status()["progress"]);
    progress("b", 0.5);
    seen.push_back(job->status()["progress"]);
    progress("a", 0.0);  // a stage reported again late does not move the bar back
    seen.push_back(job->status()["progress"]);
    BakeResult r;
    r.needed = true;
    r.key = "k";
    return r;
  });
  EXPECT_EQ(seen, (std::vector<double>{0.0, 0.25, 0.625, 0.625}));
  EXPECT_EQ(job->state(), BakeJob::State::Done);
  EXPECT_EQ(job->status()["progress"], 1.0);
  EXPECT_EQ(job->status()["key"], "k");
}

TEST(BakeJobs, SameIdentitySameJobUntilItFailsOrIsCancelled) {
  BakeJobs jobs;
  bool created = false;
  auto a = submit(jobs, "x", &created);
  EXPECT_TRUE(created);
  EXPECT_EQ(submit(jobs, "x", &created), a);
  EXPECT_FALSE(created);
  EXPECT_NE(submit(jobs, "y")->id(), a->id());
  EXPECT_EQ(a->id(), BakeJobs::id_for("x"));
  a->run([](const BakeProgress&) -> BakeResult { throw std::runtime_error("no medium"); });
  EXPECT_EQ(a->state(), BakeJob::State::Failed);
  EXPECT_EQ(a->status()["error"], "no medium");
  auto b = submit(jobs, "x", &created);
  EXPECT_TRUE(created);
  EXPECT_NE(b, a);
  EXPECT_EQ(b->id(), a->id());
}

TEST(BakeJobs, CancelQueuedRunningAndFinished) {
  BakeJobs jobs;
  auto queued = submit(jobs, "q");
  EXPECT_TRUE(queued->cancel());
  EXPECT_EQ(queued->state(), BakeJob::State::Cancelled);  // at once, not when it would have run
  bool ran = false;
  queued->run([&](const BakeProgress&) {
    ran = true;
    return BakeResult{};
  });
  EXPECT_FALSE(ran);
  bool created = false;
  EXPECT_NE(submit(jobs, "q", &created), queued);  // asking again bakes again
  EXPECT_TRUE(created);

  auto running = submit(jobs, "r");
  running->run([&](const BakeProgress& progress) {
    progress("a", 0.5);
    EXPECT_TRUE(running->cancel());
    EXPECT_NE(submit(jobs, "r"), running);  // being cancelled: a new POST gets a new job
    progress("a", 0.6);                     // throws BakeCancelled
    ADD_FAILURE() << "the progress report after cancel() did not stop the bake";
    return BakeResult{};
  });
  EXPECT_EQ(running->state(), BakeJob::State::Cancelled);
  EXPECT_FALSE(running->cancel());  // finished: nothing to cancel
}

TEST(BakeJobs, LimitsActiveJobsAndForgetsOldFinishedOnes) {
  BakeJobs jobs;
  std::vector<std::shared_ptr<BakeJob>> active;
  for (int i = 0; i < BakeJobs::kMaxActive; ++i)
    active.push_back(submit(jobs, numbered("a", size_t(i))));
  EXPECT_THROW(submit(jobs, "one more"), BakeJobs::Busy);
  EXPECT_FALSE(jobs.find(BakeJobs::id_for("one more")));
  EXPECT_EQ(submit(jobs, "a0"), active[0]);  // an existing job is still found
  active[0]->run([](const BakeProgress&) { return BakeResult{}; });
  EXPECT_NO_THROW(submit(jobs, "one more"));
  BakeJobs many;
  auto first = submit(many, "first");
  first->run([](const BakeProgress&) { return BakeResult{}; });
  for (size_t i = 0; i < BakeJobs::kMaxKept + 5; ++i) {
    auto j = submit(many, numbered("job", i));
    j->run([](const BakeProgress&) { return BakeResult{}; });
  }
  EXPECT_LE(many.list().size(), BakeJobs::kMaxKept);
  EXPECT_FALSE(many.find(first->id()));  // the oldest finished went first
}

}  // namespace
}  // namespace scatter
