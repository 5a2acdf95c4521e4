#include "bake/cache.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace scatter {
namespace {

namespace fs = std::filesystem;

// File layout, all integers little-endian:
//   magic "SCATBAKE" (8) | format version u32 | payload size u64 | key (32, the hex decoded) |
//   SHA-256 of payload (32) | payload
// The key names whose product this is, so that a whole, valid file under another key's name (a
// copy, a rename, a sync tool's mix-up) is not served as this key's product.
constexpr std::string_view kMagic = "SCATBAKE";
constexpr size_t kKeyAt = 8 + 4 + 8, kChecksumAt = kKeyAt + 32, kHeaderSize = kChecksumAt + 32;

Digest to_digest(std::string_view bytes) {
  Digest d{};
  std::copy_n(bytes.begin(), std::min(bytes.size(), d.size()), d.begin());
  return d;
}

void put_le(std::string& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

uint64_t get_le(const char* in, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t(static_cast<unsigned char>(in[i])) << (8 * i);
  return v;
}

// The 32 bytes a 64-character key spells (the caller has checked is_bake_key).
std::string key_bytes(const std::string& key_hex) {
  auto nibble = [](char c) { return c <= '9' ? c - '0' : c - 'a' + 10; };
  std::string bytes(key_hex.size() / 2, '\0');
  for (size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = static_cast<char>(nibble(key_hex[2 * i]) << 4 | nibble(key_hex[2 * i + 1]));
  return bytes;
}

std::string make_header(const std::string& key_hex, std::string_view payload) {
  std::string h(kMagic);
  put_le(h, kBakeFormatVersion, 4);
  put_le(h, payload.size(), 8);
  h += key_bytes(key_hex);
  const Digest d = sha256(payload);
  h.append(reinterpret_cast<const char*>(d.data()), d.size());
  return h;
}

struct FileRead {
  enum Outcome { kAbsent, kUnreadable, kCorrupt, kOk } outcome;
  std::string payload_or_problem;
};

// Reads and verifies one .bake file, which must hold key_hex's product. The length is taken from
// the open stream, so a file renamed over this one meanwhile does not mix with it.
FileRead read_bake_file(const fs::path& path, const std::string& key_hex) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return {ec ? FileRead::kUnreadable : FileRead::kAbsent, ec.message()};
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return {FileRead::kUnreadable, "cannot open"};
  const auto length = static_cast<uint64_t>(in.tellg());
  if (length < kHeaderSize)
    return {FileRead::kCorrupt, "truncated: " + std::to_string(length) + " bytes, no full header"};
  char header[kHeaderSize];
  in.seekg(0);
  if (!in.read(header, kHeaderSize)) return {FileRead::kUnreadable, "cannot read the header"};
  if (std::string_view(header, kMagic.size()) != kMagic) return {FileRead::kCorrupt, "bad magic"};
  if (const uint64_t version = get_le(header + 8, 4); version != kBakeFormatVersion)
    return {FileRead::kCorrupt, "format version " + std::to_string(version) + ", expected " +
                                    std::to_string(kBakeFormatVersion)};
  // Checked before allocating, so a garbage size never asks for more memory than the file holds.
  const uint64_t size = get_le(header + 12, 8);
  if (size != length - kHeaderSize)
    return {FileRead::kCorrupt, "header says " + std::to_string(size) +
                                    " payload bytes, file has " +
                                    std::to_string(length - kHeaderSize)};
  if (const std::string_view key(header + kKeyAt, 32); key != key_bytes(key_hex))
    return {FileRead::kCorrupt,
            "holds the product of key " + to_hex(to_digest(key)) + ", not of this one"};
  std::string payload(size, '\0');
  if (!in.read(payload.data(), static_cast<std::streamsize>(size)))
    return {FileRead::kUnreadable, "cannot read the payload"};
  if (!std::equal(header + kChecksumAt, header + kHeaderSize, sha256(payload).begin(),
                  [](char a, unsigned char b) { return static_cast<unsigned char>(a) == b; }))
    return {FileRead::kCorrupt, "payload checksum mismatch"};
  return {FileRead::kOk, std::move(payload)};
}

void check_key(const std::string& key_hex) {
  if (!is_bake_key(key_hex))
    throw std::invalid_argument("bake key must be 64 lowercase hex characters, got \"" +
                                key_hex.substr(0, 80) + "\"");
}

}  // namespace

bool is_bake_key(std::string_view key_hex) {
  if (key_hex.size() != 64) return false;
  for (char c : key_hex)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

// ---- BakeKey ----

BakeKey& BakeKey::add_part(char type, std::string_view name, std::string_view value) {
  // Length prefixes make the serialisation unambiguous whatever bytes names and values hold.
  parts_ += type;
  parts_ += ' ' + std::to_string(name.size()) + ':';
  parts_ += name;
  parts_ += ' ' + std::to_string(value.size()) + ':';
  parts_ += value;
  parts_ += '\n';
  return *this;
}

BakeKey& BakeKey::add(std::string_view name, std::string_view value) {
  return add_part('s', name, value);
}

BakeKey& BakeKey::add(std::string_view name, double value) {
  // Shortest text that reads back to the same double: exact, and independent of the locale.
  char buf[64];
  const auto end = std::to_chars(buf, buf + sizeof buf, value).ptr;
  return add_part('n', name, std::string_view(buf, end - buf));
}

BakeKey& BakeKey::add_bytes(std::string_view name, std::string_view bytes) {
  return add_part('b', name, sha256_hex(bytes));
}

std::string BakeKey::hex() const {
  return sha256_hex("scatter-bake-key " + std::to_string(kBakeFormatVersion) + "\n" + parts_);
}

// ---- BakeCache ----

BakeCache::BakeCache(std::filesystem::path dir, size_t memory_budget_bytes)
    : dir_(std::move(dir)), memory_budget_(memory_budget_bytes) {
  if (dir_.empty()) return;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_))
    throw std::runtime_error("cannot create bake cache directory " + dir_.string() + ": " +
                             (ec ? ec.message() : "not a directory"));
}

std::optional<std::shared_ptr<const std::string>> BakeCache::get(const std::string& key_hex) {
  check_key(key_hex);
  uint64_t writes_seen = 0;
  {
    std::lock_guard lock(mutex_);
    if (auto it = index_.find(key_hex); it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      ++stats_.memory_hits;
      return it->second->second;
    }
    writes_seen = disk_writes_;
    if (dir_.empty()) {
      ++stats_.misses;
      return std::nullopt;
    }
  }

  // Disk I/O without the lock; other keys stay served from memory meanwhile.
  const fs::path path = file_path(key_hex);
  FileRead read = read_bake_file(path, key_hex);
  if (read.outcome == FileRead::kOk) {
    std::error_code touch;
    fs::last_write_time(path, fs::file_time_type::clock::now(), touch);  // recently used
    auto product = std::make_shared<const std::string>(std::move(read.payload_or_problem));
    std::lock_guard lock(mutex_);
    ++stats_.disk_hits;
    // A put() of the same key may have landed meanwhile; keep its copy.
    if (auto it = index_.find(key_hex); it != index_.end()) return it->second->second;
    remember(key_hex, product);
    return product;
  }
  if (read.outcome == FileRead::kCorrupt) {
    const std::string fate = quarantine(path, writes_seen);
    spdlog::warn("event=bake_cache_corrupt file=\"{}\" problem=\"{}\" fate=\"{}\" outcome=miss",
                 path.string(), read.payload_or_problem, fate);
  } else if (read.outcome == FileRead::kUnreadable) {
    spdlog::warn("event=bake_cache_unreadable file=\"{}\" problem=\"{}\" outcome=miss",
                 path.string(), read.payload_or_problem);
  }
  std::lock_guard lock(mutex_);
  ++stats_.misses;
  return std::nullopt;
}

std::string BakeCache::quarantine(const fs::path& path, uint64_t writes_seen) {
  std::lock_guard lock(mutex_);
  ++stats_.corrupt;
  // Under the lock, so that no put() renames a fresh file into place between the check and
  // this rename: a file written since we read the bad one is left alone.
  if (disk_writes_ != writes_seen) return "left in place, a fresh copy was written meanwhile";
  fs::path aside = path;
  aside.replace_extension(".corrupt");
  std::error_code ec;
  fs::rename(path, aside, ec);
  if (!ec) return "moved aside to " + aside.string();
  if (ec == std::errc::no_such_file_or_directory) return "already gone";
  const std::string why = ec.message();
  fs::remove(path, ec);
  if (!ec) return "deleted (cannot move it aside: " + why + ")";
  return "cannot move it aside (" + why + ") nor delete it (" + ec.message() + ")";
}

void BakeCache::put(const std::string& key_hex, std::string bytes) {
  check_key(key_hex);
  auto product = std::make_shared<const std::string>(std::move(bytes));
  {
    std::lock_guard lock(mutex_);
    ++stats_.stores;
    remember(key_hex, product);
  }
  if (!dir_.empty()) {
    write_file(key_hex, *product);
    if (disk_budget_ > 0) trim_disk(key_hex);
  }
}

void BakeCache::set_disk_budget(uint64_t bytes) {
  disk_budget_ = bytes;
}

void BakeCache::trim_disk(const std::string& keep_key) {
  struct Entry {
    fs::file_time_type time;
    uint64_t size;
    fs::path path;
  };
  std::vector<Entry> files;
  uint64_t total = 0;
  const auto now = fs::file_time_type::clock::now();
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    std::error_code fe;
    const std::string name = e.path().filename().string();
    auto time = e.last_write_time(fe);
    if (fe) continue;
    if (name.find(".bake.tmp-") != std::string::npos) {
      if (now - time > std::chrono::hours(1)) fs::remove(e.path(), fe);
      continue;
    }
    if (e.path().extension() != ".bake" || name.substr(0, 64) == keep_key) {
      if (e.path().extension() == ".bake") total += e.file_size(fe);
      continue;
    }
    uint64_t size = e.file_size(fe);
    if (fe) continue;
    files.push_back({time, size, e.path()});
    total += size;
  }
  std::sort(files.begin(), files.end(),
            [](const Entry& a, const Entry& b) { return a.time < b.time; });
  for (const Entry& f : files) {
    if (total <= disk_budget_) break;
    std::error_code re;
    if (fs::remove(f.path, re)) {
      total -= f.size;
      std::lock_guard lock(mutex_);
      ++stats_.disk_evictions;
    }
  }
}

void BakeCache::write_file(const std::string& key_hex, const std::string& bytes) {
  uint64_t n = 0;
  {
    std::lock_guard lock(mutex_);
    n = temp_counter_++;
  }
  const fs::path final_path = file_path(key_hex);
  const fs::path temp_path =
      dir_ / (key_hex + ".bake.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n));
  std::error_code ec;
  {
    std::ofstream out(temp_path, std::ios::binary | std::ios::trunc);
    out << make_header(key_hex, bytes);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) ec = std::make_error_code(std::errc::io_error);
  }
  if (!ec) {
    // rename() replaces the old file atomically: readers see the old bytes or the new, whole.
    std::lock_guard lock(mutex_);
    fs::rename(temp_path, final_path, ec);
    if (!ec) ++disk_writes_;
  }
  if (ec) {
    std::error_code ignored;
    fs::remove(temp_path, ignored);
    spdlog::warn("event=bake_cache_write_failed file=\"{}\" problem=\"{}\" outcome=memory_only",
                 final_path.string(), ec.message());
  }
}

void BakeCache::remember(const std::string& key_hex, Product product) {
  if (auto it = index_.find(key_hex); it != index_.end()) {
    memory_bytes_ -= it->second->second->size();
    lru_.erase(it->second);
    index_.erase(it);
  }
  // A product larger than the whole budget would evict everything and then itself.
  if (product->size() > memory_budget_) return;
  memory_bytes_ += product->size();
  lru_.emplace_front(key_hex, std::move(product));
  index_[key_hex] = lru_.begin();
  while (memory_bytes_ > memory_budget_) {
    const auto& [key, oldest] = lru_.back();
    memory_bytes_ -= oldest->size();
    index_.erase(key);
    lru_.pop_back();
  }
}

CacheStats BakeCache::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

const std::filesystem::path& BakeCache::dir() const {
  return dir_;
}

size_t BakeCache::memory_bytes() const {
  std::lock_guard lock(mutex_);
  return memory_bytes_;
}

std::filesystem::path BakeCache::file_path(const std::string& key_hex) const {
  check_key(key_hex);
  return dir_.empty() ? fs::path() : dir_ / (key_hex + ".bake");
}

std::filesystem::path BakeCache::default_dir() {
  // The XDG spec says a relative XDG_CACHE_HOME is invalid and must be ignored.
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg && fs::path(xdg).is_absolute())
    return fs::path(xdg) / "scatter";
  if (const char* home = std::getenv("HOME"); home && *home)
    return fs::path(home) / ".cache" / "scatter";
  return "/tmp/scatter-cache";
}

}  // namespace scatter
