// --cache-dir, shared by the verbs that bake: where bake products live on disk.
#pragma once

#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "bake/cache.hpp"

namespace scatter::tools {

void add_cache_dir_option(CLI::App* cmd, std::string& dir);
// "" -> BakeCache::default_dir(); "none" -> memory only.
std::unique_ptr<BakeCache> open_cache(const std::string& dir);

}  // namespace scatter::tools
