#include "tools/settings_option.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace scatter::tools {

Settings parse_settings(const std::vector<std::string>& pairs) {
  Settings out;
  for (const auto& p : pairs) {
    auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0)
      throw ValidationError("--set", "expects key=value, got \"" + p + "\"");
    std::string key = p.substr(0, eq), value = p.substr(eq + 1);
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size() || !std::isfinite(v))
      throw ValidationError("--set " + key, "expects a number, got \"" + value + "\"");
    out[key] = v;
  }
  return out;
}

}  // namespace scatter::tools
