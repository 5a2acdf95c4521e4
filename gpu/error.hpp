#pragma once

#include <stdexcept>
#include <string>

namespace scatter::gpu {

// A GPU context could not be created or a program failed to build; the message says which and why.
class GpuError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace scatter::gpu
