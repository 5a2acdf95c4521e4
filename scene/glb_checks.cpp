// check_glb (scene/mesh_checks.hpp): a GLB's framing, then what its JSON says of its buffers.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/mesh_checks.hpp"

namespace scatter {
namespace {

constexpr int kMaxGlbDepth = 64;  // objects and arrays inside one another in the JSON chunk
constexpr uint32_t kJsonChunk = 0x4E4F534A, kBinChunk = 0x004E4942;

[[noreturn]] void fail(const std::string& problem) {
  throw std::runtime_error("GLB: " + problem);
}

// How deep the JSON text's objects and arrays nest (outside strings).
int nesting(std::string_view text) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      deepest = std::max(deepest, ++depth);
      if (deepest > kMaxGlbDepth) return deepest;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return deepest;
}

// The bytes a data URI's base64 payload decodes to (0 for another URI: the one-file upload has
// nothing else to serve, so assimp finds no data).
uint64_t data_uri_bytes(const std::string& uri) {
  if (uri.rfind("data:", 0) != 0) return 0;
  const size_t comma = uri.find(',');
  if (comma == std::string::npos || uri.find(";base64", 5) > comma) return 0;
  uint64_t chars = uri.size() - comma - 1;
  uint64_t pad = 0;
  for (size_t i = uri.size(); i > comma + 1 && uri[i - 1] == '='; --i) ++pad;
  return (chars - pad) * 3 / 4;
}

// The field `key` of `item` (what names it: "accessor 3") as a whole number of at most `most`, or
// `fallback` when absent (-1: required).
uint64_t whole(const nlohmann::json& item, const char* key, uint64_t most, const std::string& what,
               int64_t fallback = -1) {
  auto it = item.find(key);
  if (it == item.end()) {
    if (fallback < 0) fail(what + " has no " + key);
    return uint64_t(fallback);
  }
  if (!it->is_number_unsigned() && !(it->is_number_integer() && it->get<int64_t>() >= 0))
    fail(what + "'s " + key + " must be a whole number");
  const uint64_t x = it->get<uint64_t>();
  if (x > most)
    fail(what + "'s " + key + " is " + std::to_string(x) + ", more than " + std::to_string(most));
  return x;
}

const nlohmann::json& list(const nlohmann::json& doc, const char* key) {
  static const nlohmann::json empty = nlohmann::json::array();
  auto it = doc.find(key);
  if (it == doc.end()) return empty;
  if (!it->is_array()) fail(std::string(key) + " must be an array");
  for (const auto& x : *it)
    if (!x.is_object()) fail(std::string("each of ") + key + " must be an object");
  return *it;
}

uint64_t component_bytes(uint64_t type, const std::string& what) {
  switch (type) {
    case 5120:
    case 5121:
      return 1;  // (un)signed byte
    case 5122:
    case 5123:
      return 2;  // (un)signed short
    case 5125:
    case 5126:
      return 4;  // unsigned int, float
    default:
      fail(what + "'s componentType " + std::to_string(type) + " is not a glTF one");
  }
}

uint64_t components(const nlohmann::json& type, const std::string& what) {
  const std::string t = type.is_string() ? type.get<std::string>() : "";
  if (t == "SCALAR") return 1;
  if (t == "VEC2") return 2;
  if (t == "VEC3") return 3;
  if (t == "VEC4" || t == "MAT2") return 4;
  if (t == "MAT3") return 9;
  if (t == "MAT4") return 16;
  fail(what + "'s type must be SCALAR, VEC2-4 or MAT2-4");
}

void check_json(std::string_view text, uint64_t bin_bytes, uint64_t file_bytes) {
  if (int d = nesting(text); d > kMaxGlbDepth)
    fail("the JSON nests more than " + std::to_string(kMaxGlbDepth) + " deep");
  nlohmann::json doc = nlohmann::json::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) fail("the JSON chunk is not a JSON object");
  const nlohmann::json& buffers = list(doc, "buffers");
  std::vector<uint64_t> buffer_bytes;
  for (size_t i = 0; i < buffers.size(); ++i) {
    const std::string what = "buffer " + std::to_string(i);
    const uint64_t n = whole(buffers[i], "byteLength", file_bytes, what);
    auto uri = buffers[i].find("uri");
    const uint64_t holds = uri == buffers[i].end()
                               ? (i == 0 ? bin_bytes : 0)
                               : data_uri_bytes(uri->is_string() ? uri->get<std::string>() : "");
    if (n > holds)
      fail(what + " says " + std::to_string(n) + " bytes, its data holds " + std::to_string(holds));
    buffer_bytes.push_back(n);
  }
  const nlohmann::json& views = list(doc, "bufferViews");
  std::vector<uint64_t> view_bytes;
  for (size_t i = 0; i < views.size(); ++i) {
    const std::string what = "bufferView " + std::to_string(i);
    const uint64_t b = whole(views[i], "buffer", buffers.size() - (buffers.empty() ? 0 : 1), what);
    if (b >= buffers.size()) fail(what + " names buffer " + std::to_string(b) + " of none");
    const uint64_t offset = whole(views[i], "byteOffset", file_bytes, what, 0);
    const uint64_t n = whole(views[i], "byteLength", file_bytes, what);
    if (offset + n > buffer_bytes[b])
      fail(what + " (" + std::to_string(offset) + " + " + std::to_string(n) +
           " bytes) runs past buffer " + std::to_string(b) + "'s " +
           std::to_string(buffer_bytes[b]));
    whole(views[i], "byteStride", 252, what, 0);
    view_bytes.push_back(n);
  }
  const nlohmann::json& accessors = list(doc, "accessors");
  for (size_t i = 0; i < accessors.size(); ++i) {
    const nlohmann::json& a = accessors[i];
    const std::string what = "accessor " + std::to_string(i);
    if (a.contains("sparse")) fail(what + " is sparse (sparse accessors are not read)");
    const uint64_t v = whole(a, "bufferView", views.size(), what);
    if (v >= views.size()) fail(what + " names bufferView " + std::to_string(v) + " of none");
    const uint64_t element = component_bytes(whole(a, "componentType", 5126, what), what) *
                             components(a.contains("type") ? a["type"] : nlohmann::json(), what);
    const uint64_t count = whole(a, "count", file_bytes, what);
    const uint64_t offset = whole(a, "byteOffset", file_bytes, what, 0);
    const uint64_t stride = std::max<uint64_t>(element, whole(views[v], "byteStride", 252, "", 0));
    if (count == 0) fail(what + " has count 0");
    // Every operand is at most the file's size (or 252): no overflow in 64 bits.
    const uint64_t end = offset + stride * (count - 1) + element;
    if (end > view_bytes[v])
      fail(what + " (" + std::to_string(count) + " elements of " + std::to_string(element) +
           " bytes, " + std::to_string(stride) + " apart, from " + std::to_string(offset) +
           ") runs past bufferView " + std::to_string(v) + "'s " + std::to_string(view_bytes[v]) +
           " bytes");
  }
  for (const auto& image : list(doc, "images"))
    if (image.contains("bufferView") &&
        whole(image, "bufferView", file_bytes, "an image") >= views.size())
      fail("an image names a bufferView of none");
  const nlohmann::json& meshes = list(doc, "meshes");
  for (size_t m = 0; m < meshes.size(); ++m) {
    auto prims = meshes[m].find("primitives");
    if (prims == meshes[m].end() || !prims->is_array()) continue;
    for (const auto& p : *prims) {
      const std::string what = "mesh " + std::to_string(m) + "'s primitive";
      if (!p.is_object()) fail(what + " must be an object");
      if (p.contains("indices") && whole(p, "indices", file_bytes, what) >= accessors.size())
        fail(what + " names indices of no accessor");
      auto attributes = p.find("attributes");
      if (attributes == p.end() || !attributes->is_object()) continue;
      for (const auto& [name, index] : attributes->items())
        if (!index.is_number_unsigned() || index.get<uint64_t>() >= accessors.size())
          fail(what + "'s attribute " + name.substr(0, 40) + " names no accessor");
    }
  }
}

}  // namespace

void check_glb(std::string_view bytes) {
  auto u32 = [&](size_t at) {
    uint32_t x = 0;
    for (int i = 3; i >= 0; --i) x = (x << 8) | static_cast<unsigned char>(bytes[at + i]);
    return x;
  };
  if (bytes.size() < 12) fail("shorter than its 12-byte header");
  if (bytes.substr(0, 4) != "glTF") fail("the file must start with glTF");
  const uint32_t version = u32(4), length = u32(8);
  if (length > bytes.size())
    fail("the header says " + std::to_string(length) + " bytes, the file holds " +
         std::to_string(bytes.size()));
  if (version != 2)
    fail("version " + std::to_string(version) + " (only glTF 2.0, version 2, is read)");
  std::string_view json, bin;
  int index = 0;
  for (size_t at = 12; at < length; ++index) {
    if (length - at < 8)
      fail("chunk " + std::to_string(index) + "'s header runs past the " + std::to_string(length) +
           " bytes");
    const uint32_t chunk = u32(at), type = u32(at + 4);
    if (chunk > length - at - 8)
      fail("chunk " + std::to_string(index) + " says " + std::to_string(chunk) + " bytes, " +
           std::to_string(length - at - 8) + " follow it");
    if (chunk % 4 != 0)
      fail("chunk " + std::to_string(index) + " says " + std::to_string(chunk) +
           " bytes, not a multiple of 4");
    if (index == 0 && type != kJsonChunk) fail("the first chunk must be the JSON");
    if (index == 0) json = bytes.substr(at + 8, chunk);
    if (index == 1 && type == kBinChunk) bin = bytes.substr(at + 8, chunk);
    at += 8 + size_t(chunk);
  }
  if (index == 0) fail("no JSON chunk");
  check_json(json, bin.size(), bytes.size());
}

}  // namespace scatter
