// --cache-dir, shared by the verbs that bake: where bake products live on disk.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "bake/cache.hpp"

namespace scatter::tools {

struct CacheOptions {
  std::string dir;       // "" -> BakeCache::default_dir(); "none" -> memory only
  size_t max_mb = 4096;  // disk budget of the directory's bake products
};

// --cache-dir and --cache-max-mb.
void add_cache_options(CLI::App* cmd, CacheOptions& options);
std::unique_ptr<BakeCache> open_cache(const CacheOptions& options);

}  // namespace scatter::tools
