// Kernels (kernels/) and shaders (shaders/) compiled into the binary by cmake/embed.cmake.
#pragma once

#include <map>
#include <string>
#include <string_view>

namespace scatter::gpu {

// Path relative to the repository root ("kernels/common/grid.cl") to its text.
const std::map<std::string, std::string_view>& embedded_sources();
// The text of one embedded file; throws std::runtime_error naming the path if it is not there.
std::string_view embedded_source(const std::string& path);

}  // namespace scatter::gpu
