#include "bake/cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

namespace scatter {
namespace {

namespace fs = std::filesystem;

constexpr size_t kHeaderSize = 84;  // magic 8 + version 4 + size 8 + key 32 + SHA-256 32

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_all(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Every byte value, so that a text-mode or NUL-terminated path somewhere would show.
std::string binary_payload(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() & 0xff);
  return s;
}

std::string key_of(const std::string& name) {
  return BakeKey().add("test", name).hex();
}

class BakeCacheTest : public ::testing::Test {
 protected:
  BakeCacheTest() {
    // Parameterised tests' names hold a '/'.
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("scatter-bake-test-" + std::to_string(::getpid()) + "-" +
                                        name + "-" + std::to_string(std::random_device{}()));
    fs::remove_all(dir_);
  }
  ~BakeCacheTest() override { fs::remove_all(dir_); }

  fs::path dir_;
};

TEST(Sha256, MatchesFipsVectors) {
  // FIPS 180-2, appendix B.1 and B.2; and the empty message.
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex(std::string("a\0b", 3)).size(), 64u);
  EXPECT_NE(sha256_hex(std::string("a\0b", 3)), sha256_hex("a"));
}

TEST(BakeKeyTest, StableOrderAndValueSensitive) {
  auto key = [](double sigma) {
    return BakeKey().add("pipeline", "single").add("sigma_s", sigma).add_bytes("mesh", "v 0 0 0");
  };
  const std::string k = key(1.5).hex();
  EXPECT_TRUE(is_bake_key(k));
  EXPECT_EQ(k, key(1.5).hex());
  EXPECT_EQ(k, key(1.5).hex());  // hex() leaves the builder as it was

  // Order.
  EXPECT_NE(BakeKey().add("a", "1").add("b", "2").hex(),
            BakeKey().add("b", "2").add("a", "1").hex());
  // Values: strings, numbers that differ in the last bit, hashed bytes.
  EXPECT_NE(k, key(2.5).hex());
  EXPECT_NE(BakeKey().add("x", 0.1).hex(), BakeKey().add("x", std::nextafter(0.1, 1.0)).hex());
  EXPECT_NE(BakeKey().add_bytes("m", "abc").hex(), BakeKey().add_bytes("m", "abd").hex());
  EXPECT_NE(BakeKey().add("p", "single").hex(), BakeKey().add("p", "lbl").hex());
  // Names, and where one part ends and the next begins.
  EXPECT_NE(BakeKey().add("a", "1").hex(), BakeKey().add("b", "1").hex());
  EXPECT_NE(BakeKey().add("a", "bc").hex(), BakeKey().add("ab", "c").hex());
  EXPECT_NE(BakeKey().add("a", "1").add("b", "2").hex(), BakeKey().add("a", "1 b 2").hex());
  EXPECT_NE(BakeKey().add("a", "1").add("b", "2").hex(), BakeKey().add("a 1:1\ns b", "2").hex());
  // A string is not the number it spells, nor bytes hashed.
  EXPECT_NE(BakeKey().add("x", "1").hex(), BakeKey().add("x", 1.0).hex());
  EXPECT_NE(BakeKey().add("x", sha256_hex("m")).hex(), BakeKey().add_bytes("x", "m").hex());
  // The empty key is a key too, and not a part-less sha256 of "".
  EXPECT_TRUE(is_bake_key(BakeKey().hex()));
  EXPECT_NE(BakeKey().hex(), sha256_hex(""));
}

TEST_F(BakeCacheTest, MemoryRoundTripIsByteIdentical) {
  BakeCache cache;  // memory only
  EXPECT_TRUE(cache.dir().empty());
  const std::string bytes = binary_payload(10000, 1);
  const std::string k = key_of("a");
  EXPECT_FALSE(cache.get(k).has_value());
  cache.put(k, bytes);
  auto got = cache.get(k);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(**got, bytes);
  EXPECT_EQ(cache.memory_bytes(), bytes.size());
  const CacheStats s = cache.stats();
  EXPECT_EQ(s.memory_hits, 1u);
  EXPECT_EQ(s.disk_hits, 0u);
  EXPECT_EQ(s.misses, 1u);
  EXPECT_EQ(s.stores, 1u);

  // Storing again replaces, and the bytes are counted once.
  cache.put(k, "shorter");
  EXPECT_EQ(**cache.get(k), "shorter");
  EXPECT_EQ(cache.memory_bytes(), 7u);
}

TEST_F(BakeCacheTest, NewCacheOnSameDirGetsDiskHit) {
  const std::string bytes = binary_payload(100000, 2);
  const std::string k = key_of("disk");
  {
    BakeCache writer(dir_);
    EXPECT_TRUE(fs::is_directory(dir_));
    writer.put(k, bytes);
  }
  const fs::path file = dir_ / (k + ".bake");
  ASSERT_TRUE(fs::exists(file));
  EXPECT_EQ(fs::file_size(file), kHeaderSize + bytes.size());
  EXPECT_EQ(read_all(file).substr(0, 8), "SCATBAKE");
  // No temporary files left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);

  BakeCache reader(dir_);
  auto got = reader.get(k);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(**got, bytes);
  EXPECT_EQ(reader.stats().disk_hits, 1u);
  // The disk hit is kept in memory for the next request.
  ASSERT_TRUE(reader.get(k).has_value());
  EXPECT_EQ(reader.stats().memory_hits, 1u);
  EXPECT_FALSE(reader.get(key_of("never stored")).has_value());
  EXPECT_EQ(reader.stats().misses, 1u);
  EXPECT_EQ(reader.stats().corrupt, 0u);
}

TEST_F(BakeCacheTest, EmptyProductRoundTripsThroughDisk) {
  const std::string k = key_of("empty");
  BakeCache(dir_).put(k, "");
  auto got = BakeCache(dir_).get(k);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(**got, "");
}

// Each way a file can go bad: detected, counted, moved out of the way, and a fresh put() works.
struct Damage {
  const char* name;
  std::function<void(std::string&)> apply;
};

class BakeCacheCorruptionTest : public BakeCacheTest,
                                public ::testing::WithParamInterface<Damage> {};

TEST_P(BakeCacheCorruptionTest, IsDetectedAndRepairedByPut) {
  const std::string bytes = binary_payload(4096, 3);
  const std::string k = key_of("corrupt");
  const fs::path file = dir_ / (k + ".bake");
  BakeCache(dir_).put(k, bytes);
  std::string contents = read_all(file);
  ASSERT_EQ(contents.size(), kHeaderSize + bytes.size());
  GetParam().apply(contents);
  write_all(file, contents);

  BakeCache cache(dir_);
  EXPECT_FALSE(cache.get(k).has_value());
  EXPECT_EQ(cache.stats().corrupt, 1u);
  EXPECT_EQ(cache.stats().misses, 1u);
  EXPECT_EQ(cache.stats().disk_hits, 0u);
  // No longer trusted: the bad file is out of the way, so a second look is a plain miss.
  EXPECT_FALSE(fs::exists(file));
  EXPECT_TRUE(fs::exists(dir_ / (k + ".corrupt")));  // kept for a post-mortem
  EXPECT_FALSE(cache.get(k).has_value());
  EXPECT_EQ(cache.stats().corrupt, 1u);
  EXPECT_EQ(cache.stats().misses, 2u);

  // The caller re-bakes and stores; the fresh copy serves this cache and the next one.
  cache.put(k, bytes);
  EXPECT_EQ(**cache.get(k), bytes);
  BakeCache next(dir_);
  auto got = next.get(k);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(**got, bytes);
  EXPECT_EQ(next.stats().disk_hits, 1u);
  EXPECT_EQ(next.stats().corrupt, 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Damages, BakeCacheCorruptionTest,
    ::testing::Values(
        Damage{"FlippedPayloadByte", [](std::string& s) { s[kHeaderSize + 1234] ^= 0x01; }},
        Damage{"FlippedChecksumByte", [](std::string& s) { s[kHeaderSize - 1] ^= 0x80; }},
        Damage{"FlippedKeyByte", [](std::string& s) { s[20] ^= 0x01; }},
        Damage{"TruncatedPayload", [](std::string& s) { s.resize(s.size() - 1); }},
        Damage{"TruncatedHeader", [](std::string& s) { s.resize(kHeaderSize / 2); }},
        Damage{"EmptyFile", [](std::string& s) { s.clear(); }},
        Damage{"ExtraByte", [](std::string& s) { s += 'x'; }},
        Damage{"GarbageHeader",
               [](std::string& s) { s.replace(0, kHeaderSize, binary_payload(kHeaderSize, 9)); }},
        Damage{"BadMagic", [](std::string& s) { s[0] = 'X'; }},
        Damage{"OtherVersion",
               [](std::string& s) { s[8] = static_cast<char>(kBakeFormatVersion + 1); }},
        Damage{"HugeSize", [](std::string& s) { s.replace(12, 8, std::string(8, '\xff')); }}),
    [](const ::testing::TestParamInfo<Damage>& p) { return std::string(p.param.name); });

// A whole, valid file under another key's name (copied, renamed) is not that key's product.
TEST_F(BakeCacheTest, AnotherKeysFileIsCorrupt) {
  const std::string a = key_of("a"), b = key_of("b");
  BakeCache(dir_).put(a, binary_payload(2000, 4));
  fs::copy_file(dir_ / (a + ".bake"), dir_ / (b + ".bake"));
  BakeCache cache(dir_);
  EXPECT_FALSE(cache.get(b).has_value());
  EXPECT_EQ(cache.stats().corrupt, 1u);
  EXPECT_TRUE(fs::exists(dir_ / (b + ".corrupt")));
  EXPECT_EQ(**cache.get(a), binary_payload(2000, 4));  // its own key still reads it
}

TEST_F(BakeCacheTest, InvalidKeysAreRejectedBeforeTouchingDisk) {
  BakeCache cache(dir_);
  const std::string good = key_of("k");
  const std::vector<std::string> bad = {
      "",
      good.substr(1),          // 63 characters
      good + "0",              // 65
      "A" + good.substr(1),    // upper case
      "g" + good.substr(1),    // not hex
      "../" + good.substr(3),  // a path
      "/etc/passwd",
      good.substr(0, 32) + "/" + good.substr(33),
      std::string(good).replace(10, 1, std::string(1, '\0')),
  };
  for (const auto& key : bad) {
    EXPECT_FALSE(is_bake_key(key)) << key;
    EXPECT_THROW(cache.get(key), std::invalid_argument) << key;
    EXPECT_THROW(cache.put(key, "x"), std::invalid_argument) << key;
  }
  EXPECT_TRUE(fs::is_empty(dir_));
  EXPECT_EQ(cache.stats().stores, 0u);
  EXPECT_EQ(cache.stats().misses, 0u);
}

TEST_F(BakeCacheTest, LruEvictsBeyondBudgetAndDiskStillServes) {
  const size_t n = 1000;
  BakeCache cache(dir_, 3 * n);
  const std::string a = key_of("a"), b = key_of("b"), c = key_of("c"), d = key_of("d");
  cache.put(a, binary_payload(n, 10));
  cache.put(b, binary_payload(n, 11));
  cache.put(c, binary_payload(n, 12));
  EXPECT_EQ(cache.memory_bytes(), 3 * n);
  ASSERT_TRUE(cache.get(a).has_value());  // a is now the most recently used; b the least
  cache.put(d, binary_payload(n, 13));
  EXPECT_EQ(cache.memory_bytes(), 3 * n);

  EXPECT_EQ(**cache.get(a), binary_payload(n, 10));
  EXPECT_EQ(**cache.get(c), binary_payload(n, 12));
  EXPECT_EQ(**cache.get(d), binary_payload(n, 13));
  EXPECT_EQ(cache.stats().memory_hits, 4u);
  EXPECT_EQ(cache.stats().disk_hits, 0u);
  auto evicted = cache.get(b);
  ASSERT_TRUE(evicted.has_value());
  EXPECT_EQ(**evicted, binary_payload(n, 11));
  EXPECT_EQ(cache.stats().disk_hits, 1u);
  EXPECT_LE(cache.memory_bytes(), 3 * n);

  // A product larger than the whole budget is not kept in memory, but disk has it.
  const std::string big = key_of("big");
  cache.put(big, binary_payload(4 * n, 14));
  EXPECT_EQ(cache.memory_bytes(), 3 * n);  // and it did not push out the others
  EXPECT_EQ(**cache.get(big), binary_payload(4 * n, 14));
  EXPECT_EQ(cache.stats().disk_hits, 2u);
}

TEST_F(BakeCacheTest, MemoryOnlyCacheForgetsWhatItEvicts) {
  BakeCache cache({}, 100);
  cache.put(key_of("a"), std::string(60, 'a'));
  cache.put(key_of("b"), std::string(60, 'b'));
  EXPECT_FALSE(cache.get(key_of("a")).has_value());
  EXPECT_EQ(**cache.get(key_of("b")), std::string(60, 'b'));
  EXPECT_EQ(cache.memory_bytes(), 60u);
}

TEST_F(BakeCacheTest, ConcurrentPutsAndGetsSeeWholeProducts) {
  BakeCache cache(dir_, 20000);  // small, so threads also evict and read back from disk
  constexpr int kThreads = 4, kKeys = 16, kRounds = 50;
  std::vector<std::thread> threads;
  std::atomic<int> wrong = 0;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (int r = 0; r < kRounds; ++r) {
        const int i = (t * 7 + r) % kKeys;
        const std::string k = key_of(std::to_string(i));
        const std::string expected = binary_payload(3000, i);
        if (auto got = cache.get(k)) {
          if (**got != expected) ++wrong;
        } else {
          cache.put(k, expected);
        }
      }
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(wrong, 0);
  const CacheStats s = cache.stats();
  EXPECT_EQ(s.corrupt, 0u);
  EXPECT_EQ(s.memory_hits + s.disk_hits + s.misses, uint64_t(kThreads * kRounds));
  EXPECT_LE(cache.memory_bytes(), 20000u);
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().extension(), ".bake") << entry.path();
}

TEST_F(BakeCacheTest, UncreatableDirectoryThrowsWithPath) {
  fs::create_directories(dir_);
  write_all(dir_ / "file", "not a directory");
  const fs::path impossible = dir_ / "file" / "cache";
  try {
    BakeCache cache(impossible);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(impossible.string()), std::string::npos) << e.what();
  }
}

TEST(BakeCacheDefaultDir, FollowsXdgThenHome) {
  // Each test runs in its own process under ctest, but restore the environment anyway.
  auto saved = [](const char* name) -> std::optional<std::string> {
    const char* v = std::getenv(name);
    return v ? std::optional<std::string>(v) : std::nullopt;
  };
  const auto xdg = saved("XDG_CACHE_HOME"), home = saved("HOME");
  ::setenv("XDG_CACHE_HOME", "/x/cache", 1);
  ::setenv("HOME", "/h", 1);
  EXPECT_EQ(BakeCache::default_dir(), fs::path("/x/cache/scatter"));
  ::setenv("XDG_CACHE_HOME", "relative", 1);  // invalid per the XDG spec
  EXPECT_EQ(BakeCache::default_dir(), fs::path("/h/.cache/scatter"));
  ::unsetenv("XDG_CACHE_HOME");
  EXPECT_EQ(BakeCache::default_dir(), fs::path("/h/.cache/scatter"));
  ::unsetenv("HOME");
  EXPECT_EQ(BakeCache::default_dir(), fs::path("/tmp/scatter-cache"));
  auto restore = [](const char* name, const std::optional<std::string>& v) {
    v ? ::setenv(name, v->c_str(), 1) : ::unsetenv(name);
  };
  restore("XDG_CACHE_HOME", xdg);
  restore("HOME", home);
}

// The disk budget: after a put the least recently used files go until the directory fits; a disk
// hit counts as a use; the file just written stays; stale temporary files are swept.
TEST_F(BakeCacheTest, DiskBudgetEvictsLeastRecentlyUsedFiles) {
  const std::string payload(1000, 'x');  // 1084 bytes on disk with the header
  {
    BakeCache writer(dir_);
    for (int i = 0; i < 4; ++i) writer.put(key_of(std::to_string(i)), payload);
  }
  // Age them: 0 oldest ... 3 newest; a crashed writer's temporary file two hours old.
  auto now = fs::file_time_type::clock::now();
  for (int i = 0; i < 4; ++i)
    fs::last_write_time(BakeCache(dir_).file_path(key_of(std::to_string(i))),
                        now - std::chrono::minutes(10 - i));
  write_all(dir_ / (key_of("tmp") + ".bake.tmp-1-1"), "half");
  fs::last_write_time(dir_ / (key_of("tmp") + ".bake.tmp-1-1"), now - std::chrono::hours(2));
  BakeCache cache(dir_, 0);             // nothing in memory: every get reads the disk
  ASSERT_TRUE(cache.get(key_of("0")));  // a use: 0 is now the newest
  cache.set_disk_budget(3 * 1084);
  cache.put(key_of("4"), payload);  // five files, room for three
  EXPECT_EQ(cache.stats().disk_evictions, 2u);
  EXPECT_FALSE(fs::exists(cache.file_path(key_of("1"))));
  EXPECT_FALSE(fs::exists(cache.file_path(key_of("2"))));
  for (const char* kept : {"0", "3", "4"})
    EXPECT_TRUE(fs::exists(cache.file_path(key_of(kept)))) << kept;
  EXPECT_FALSE(fs::exists(dir_ / (key_of("tmp") + ".bake.tmp-1-1")));
  // A budget smaller than one product still keeps the one just written.
  cache.set_disk_budget(10);
  cache.put(key_of("5"), payload);
  EXPECT_TRUE(fs::exists(cache.file_path(key_of("5"))));
  EXPECT_FALSE(fs::exists(cache.file_path(key_of("4"))));
}

}  // namespace
}  // namespace scatter
