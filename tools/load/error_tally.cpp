#include "tools/load/error_tally.hpp"

namespace scatter::load {

void ErrorTally::add(const std::string& kind, const std::string& detail) {
  // Long messages (a server error may quote a whole field) are cut so that they group.
  ++counts_[kind][detail.size() > 160 ? detail.substr(0, 160) + "..." : detail];
}

void ErrorTally::merge(const ErrorTally& other) {
  for (const auto& [kind, details] : other.counts_)
    for (const auto& [detail, n] : details) counts_[kind][detail] += n;
}

long long ErrorTally::count(const std::string& kind) const {
  auto it = counts_.find(kind);
  if (it == counts_.end()) return 0;
  long long n = 0;
  for (const auto& [detail, k] : it->second) n += k;
  return n;
}

long long ErrorTally::total() const {
  long long n = 0;
  for (const auto& [kind, details] : counts_) n += count(kind);
  return n;
}

nlohmann::json ErrorTally::to_json() const {
  nlohmann::json j = {{"total", total()}};
  for (const auto& [kind, details] : counts_) j[kind] = details;
  return j;
}

}  // namespace scatter::load
