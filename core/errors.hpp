// The errors that many layers throw and the REST API answers with a status of their own:
// ValidationError (bad input, 400) and GpuError (no GPU context, or a program that does not
// build, 503). core/ is the lowest layer: it includes only the standard library, so that
// protocol/, scene/, gpu/, pipelines/, bake/, server/ and tools/ may all include it.
#pragma once

#include <stdexcept>
#include <string>

namespace scatter {

// Input that fails validation: `field` is its full path ("scene.medium.sigma_s[1]", or empty),
// and what() is "field: problem".
class ValidationError : public std::runtime_error {
 public:
  ValidationError(std::string field, const std::string& problem)
      : std::runtime_error(field.empty() ? problem : field + ": " + problem),
        field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

}  // namespace scatter

namespace scatter::gpu {

// A GPU context could not be created or a program failed to build; the message says which and why.
class GpuError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace scatter::gpu
