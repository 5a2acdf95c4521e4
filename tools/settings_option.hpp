// "--set key=value" pairs, shared by the verbs that pass settings to a pipeline.
#pragma once

#include <string>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace scatter::tools {

// Throws ValidationError for a pair that is not key=number.
Settings parse_settings(const std::vector<std::string>& pairs);

}  // namespace scatter::tools
