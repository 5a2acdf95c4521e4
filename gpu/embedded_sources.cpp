#include "gpu/embedded_sources.hpp"

#include <stdexcept>

namespace scatter::gpu {

std::string_view embedded_source(const std::string& path) {
  const auto& all = embedded_sources();
  auto it = all.find(path);
  if (it == all.end()) throw std::runtime_error("no embedded kernel or shader named " + path);
  return it->second;
}

}  // namespace scatter::gpu
