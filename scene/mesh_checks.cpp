#include "scene/mesh_checks.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace scatter {
namespace {

// Assimp's line ends (ParsingUtils.h IsLineEnd) and spaces (IsSpace).
bool line_end(char c) {
  return c == '\r' || c == '\n' || c == '\f';
}
bool space(char c) {
  return c == ' ' || c == '\t';
}
constexpr size_t kMaxLine = 4000;  // assimp copies a line into char[4096]

class OffReader {
 public:
  explicit OffReader(std::string_view text) : text_(text) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw std::runtime_error("OFF line " + std::to_string(line_number()) + ": " + problem);
  }

  // The header's tokens: spaces, line ends and '#' comment lines are skipped (OFFLoader's
  // NextToken).
  std::string_view token() {
    skip_to_token();
    size_t start = pos_;
    while (pos_ < text_.size() && !space(text_[pos_]) && !line_end(text_[pos_])) ++pos_;
    return text_.substr(start, pos_ - start);
  }

  void skip_to_token() {
    for (;;) {
      while (pos_ < text_.size() && (space(text_[pos_]) || line_end(text_[pos_]))) ++pos_;
      if (pos_ >= text_.size() || text_[pos_] != '#') return;
      while (pos_ < text_.size() && !line_end(text_[pos_])) ++pos_;
    }
  }

  // The data's lines (ParsingUtils' GetNextLine): up to a line end; runs of line ends (blank lines)
  // are skipped, a line of spaces is not. Empty at the end of the text.
  bool line(std::vector<std::string_view>& tokens) {
    tokens.clear();
    if (pos_ >= text_.size()) return false;
    line_start_ = pos_;
    size_t start = pos_;
    while (pos_ < text_.size() && !line_end(text_[pos_])) ++pos_;
    if (pos_ - start > kMaxLine) fail("is longer than " + std::to_string(kMaxLine) + " characters");
    std::string_view l = text_.substr(start, pos_ - start);
    while (pos_ < text_.size() && line_end(text_[pos_])) ++pos_;
    for (size_t i = 0; i < l.size();) {
      while (i < l.size() && space(l[i])) ++i;
      if (i >= l.size() || l[i] == '#') break;
      size_t t = i;
      while (i < l.size() && !space(l[i])) ++i;
      tokens.push_back(l.substr(t, i - t));
    }
    return true;
  }

  size_t line_number() const {
    size_t n = 1;
    for (size_t i = 0; i < line_start_ && i < text_.size(); ++i) n += text_[i] == '\n';
    return n;
  }
  void mark() { line_start_ = pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t line_start_ = 0;
};

bool parse_count(std::string_view t, unsigned long long max, unsigned long long& out) {
  if (t.empty() || t.size() > 19) return false;
  for (char c : t)
    if (c < '0' || c > '9') return false;
  auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  return ec == std::errc() && end == t.data() + t.size() && out <= max;
}

bool parse_real(std::string_view t) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  double v = 0;
  auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && ec == std::errc() && end == t.data() + t.size() && std::isfinite(v);
}

}  // namespace

void check_off_text(std::string_view text) {
  if (text.find('\0') != std::string_view::npos)
    throw std::runtime_error("OFF: the text holds a NUL byte");
  OffReader in(text);
  in.skip_to_token();
  in.mark();
  std::string_view keyword = in.token();
  // [ST][C][N][4][n]OFF, in this order (OFFLoader's header parser).
  std::string_view k = keyword;
  auto flag = [&](std::string_view prefix) {
    bool has = k.substr(0, prefix.size()) == prefix && k.size() > prefix.size();
    if (has) k.remove_prefix(prefix.size());
    return has;
  };
  bool st = flag("ST"), colors = flag("C"), normals = flag("N"), homogeneous = flag("4"),
       dimension = flag("n");
  if (k != "OFF") in.fail("the file must start with OFF (or COFF, NOFF, STOFF, 4OFF, nOFF ...)");
  unsigned long long dims = 3, nv = 0, nf = 0, ne = 0;
  constexpr unsigned long long kMax = std::numeric_limits<unsigned>::max();
  in.skip_to_token();
  in.mark();
  if (dimension && (!parse_count(in.token(), 3, dims) || dims < 1))
    in.fail("the dimension after nOFF must be 1, 2 or 3");
  in.skip_to_token();
  in.mark();
  if (!parse_count(in.token(), kMax, nv) || !parse_count(in.token(), kMax, nf) ||
      !parse_count(in.token(), kMax, ne))
    in.fail("the header needs three counts: vertices, faces, edges");
  if (nv == 0 || nf == 0) in.fail("the header counts no vertices or no faces");
  in.skip_to_token();

  size_t per_vertex =
      dims + (homogeneous ? 1 : 0) + (normals ? 3 : 0) + (colors ? 1 : 0) + (st ? 2 : 0);
  std::vector<std::string_view> tokens;
  for (unsigned long long v = 0; v < nv; ++v) {
    if (!in.line(tokens))
      in.fail("the header counts " + std::to_string(nv) + " vertices, the file holds " +
              std::to_string(v));
    if (tokens.size() < per_vertex)
      in.fail("vertex " + std::to_string(v) + " needs " + std::to_string(per_vertex) + " numbers");
    for (std::string_view t : tokens)
      if (!parse_real(t))
        in.fail("vertex " + std::to_string(v) + ": \"" + std::string(t.substr(0, 40)) +
                "\" is not a finite number");
  }
  for (unsigned long long f = 0; f < nf; ++f) {
    if (!in.line(tokens))
      in.fail("the header counts " + std::to_string(nf) + " faces, the file holds " +
              std::to_string(f));
    unsigned long long n = 0;
    if (tokens.empty() || !parse_count(tokens[0], 9, n) || n < 3)
      in.fail("face " + std::to_string(f) + " must start with its vertex count, 3 to 9");
    if (tokens.size() < n + 1)
      in.fail("face " + std::to_string(f) + " names fewer than " + std::to_string(n) + " vertices");
    for (size_t i = 1; i <= n; ++i) {
      unsigned long long index = 0;
      if (!parse_count(tokens[i], kMax, index) || index >= nv)
        in.fail("face " + std::to_string(f) + " names vertex \"" +
                std::string(tokens[i].substr(0, 40)) + "\"; there are " + std::to_string(nv) +
                " (0 to " + std::to_string(nv - 1) + ")");
    }
    for (size_t i = n + 1; i < tokens.size(); ++i)  // a face's colour may follow its indices
      if (!parse_real(tokens[i]))
        in.fail("face " + std::to_string(f) + " has a trailing token that is not a number");
  }
  while (in.line(tokens))
    if (!tokens.empty())
      in.fail("holds more than the " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
              " faces its header counts");
}

}  // namespace scatter

namespace scatter {
namespace {

size_t ply_type_size(std::string_view t) {
  static const std::pair<std::string_view, size_t> kTypes[] = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  for (const auto& [name, size] : kTypes)
    if (t == name) return size;
  return 0;
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  for (size_t i = 0; i < line.size();) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

struct PlyProperty {
  size_t size = 0;        // of the value, or of a list's items
  size_t count_size = 0;  // of a list's length field; 0 for a scalar
};
struct PlyElement {
  unsigned long long count = 0;
  std::vector<PlyProperty> properties;
};

// One row per line, blank lines apart: a number per scalar, a length and that many numbers per
// list.
void check_ply_ascii(std::string_view body, const std::vector<PlyElement>& elements) {
  size_t at = 0, line_no = 0;
  for (size_t e = 0; e < elements.size(); ++e)
    for (unsigned long long row = 0; row < elements[e].count; ++row) {
      std::vector<std::string_view> w;
      while (w.empty()) {
        if (at >= body.size())
          throw std::runtime_error("PLY: element " + std::to_string(e) + " has " +
                                   std::to_string(row) + " rows, its header says " +
                                   std::to_string(elements[e].count));
        size_t nl = std::min(body.find('\n', at), body.size());
        std::string_view line = body.substr(at, nl - at);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        w = split_words(line);
        at = nl + 1;
        ++line_no;
      }
      auto fail = [&] {
        throw std::runtime_error("PLY data line " + std::to_string(line_no) + ": row " +
                                 std::to_string(row) + " of element " + std::to_string(e) +
                                 " does not match the header's properties");
      };
      size_t k = 0;
      for (const PlyProperty& p : elements[e].properties) {
        unsigned long long n = 1;
        if (p.count_size && (k >= w.size() || !parse_count(w[k++], w.size(), n))) fail();
        for (unsigned long long i = 0; i < n; ++i)
          if (k >= w.size() || !parse_real(w[k++])) fail();
      }
      if (k != w.size()) fail();
    }
}

// Walks the rows: each list's length, read in the file's byte order, must leave the row inside the
// data.
void check_ply_binary(std::string_view body, const std::vector<PlyElement>& elements,
                      bool big_endian) {
  size_t at = 0;
  for (size_t e = 0; e < elements.size(); ++e)
    for (unsigned long long row = 0; row < elements[e].count; ++row)
      for (const PlyProperty& p : elements[e].properties) {
        unsigned long long n = 1;
        if (p.count_size) {
          if (body.size() - at < p.count_size)
            n = ~0ull;
          else {
            n = 0;
            for (size_t b = 0; b < p.count_size; ++b) {
              size_t i = big_endian ? b : p.count_size - 1 - b;
              n = (n << 8) | static_cast<unsigned char>(body[at + i]);
            }
            at += p.count_size;
          }
        }
        if (n > (body.size() - at) / p.size)
          throw std::runtime_error("PLY: the data ends inside row " + std::to_string(row) +
                                   " of element " + std::to_string(e) + " (the header counts " +
                                   std::to_string(elements[e].count) + " rows)");
        at += n * p.size;
      }
}

}  // namespace

void check_ply(std::string_view bytes) {
  constexpr size_t kMaxHeader = 64 << 10;
  size_t end = bytes.find("end_header");
  if (end == std::string_view::npos || end > kMaxHeader)
    throw std::runtime_error("PLY: no end_header line in the first " + std::to_string(kMaxHeader) +
                             " bytes");
  size_t data = bytes.find('\n', end);
  if (data == std::string_view::npos)
    throw std::runtime_error("PLY: end_header is the last line; there is no data");
  std::string_view header = bytes.substr(0, data + 1);
  if (header.find('\0') != std::string_view::npos)
    throw std::runtime_error("PLY: the header holds a NUL byte");
  std::vector<PlyElement> elements;
  std::string format;
  size_t line_no = 0;
  for (size_t at = 0; at < header.size();) {
    size_t nl = header.find('\n', at);
    std::string_view line = header.substr(at, nl - at);
    at = nl + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    auto fail = [&](const std::string& problem) -> void {
      throw std::runtime_error("PLY header line " + std::to_string(line_no) + ": " + problem);
    };
    auto w = split_words(line);
    if (line_no == 1) {
      if (line != "ply") fail("the file must start with a line \"ply\"");
      continue;
    }
    if (w.empty()) fail("is empty");
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (line_no == 2) {
      if (w[0] != "format" || w.size() != 3 || w[2] != "1.0" ||
          (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        fail("must be \"format ascii|binary_little_endian|binary_big_endian 1.0\"");
      format = w[1];
    } else if (format.empty()) {
      fail("the format line must follow \"ply\"");
    } else if (w[0] == "element") {
      PlyElement e;
      if (w.size() != 3 || !parse_count(w[2], std::numeric_limits<unsigned>::max(), e.count))
        fail("must be \"element NAME COUNT\"");
      elements.push_back(e);
    } else if (w[0] == "property") {
      if (elements.empty()) fail("a property before any element");
      if (w.size() == 5 && w[1] == "list" && ply_type_size(w[2]) && ply_type_size(w[3]))
        elements.back().properties.push_back({ply_type_size(w[3]), ply_type_size(w[2])});
      else if (w.size() == 3 && ply_type_size(w[1]))
        elements.back().properties.push_back({ply_type_size(w[1]), 0});
      else
        fail("must be \"property TYPE NAME\" or \"property list TYPE TYPE NAME\"");
    } else if (w[0] == "end_header" && w.size() == 1) {
      if (at != header.size()) fail("end_header must end the header");
    } else {
      fail("\"" + std::string(w[0].substr(0, 40)) + "\" is not a PLY header keyword");
    }
  }
  if (elements.empty()) throw std::runtime_error("PLY: the header declares no elements");
  std::string_view body = bytes.substr(header.size());
  if (format == "ascii")
    check_ply_ascii(body, elements);
  else
    check_ply_binary(body, elements, format == "binary_big_endian");
}

void check_stl(std::string_view bytes) {
  if (bytes.size() < 84) return;  // too short for binary: assimp reads it as text or refuses it
  uint32_t count = 0;
  for (int i = 3; i >= 0; --i) count = (count << 8) | static_cast<unsigned char>(bytes[80 + i]);
  // Assimp takes the file as binary when 84 + 50 x count, in 32 bits, equals its size.
  const uint32_t wrapped = count * 50u + 84u;
  const uint64_t needed = uint64_t(count) * 50 + 84;
  if (wrapped == bytes.size() && needed != bytes.size())
    throw std::runtime_error("STL: the binary header counts " + std::to_string(count) +
                             " facets, " + std::to_string(needed) + " bytes; the file holds " +
                             std::to_string(bytes.size()));
}

}  // namespace scatter
