// Errors counted by kind ("refused", "server", "disconnect", ...) and detail (a status, a message).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace scatter::load {

class ErrorTally {
 public:
  void add(const std::string& kind, const std::string& detail);
  void merge(const ErrorTally& other);
  long long total() const;
  long long count(const std::string& kind) const;
  // {"total": n, "<kind>": {"<detail>": n, ...}, ...}
  nlohmann::json to_json() const;

 private:
  std::map<std::string, std::map<std::string, long long>> counts_;
};

}  // namespace scatter::load
