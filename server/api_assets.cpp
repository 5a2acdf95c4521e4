// POST/GET /api/assets: uploads checked and stored under their content id, and the lookup that
// lets a scene name them.
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "bake/cache.hpp"
#include "protocol/json_reader.hpp"
#include "scene/density.hpp"
#include "scene/mesh.hpp"
#include "server/api.hpp"
#include "server/api_util.hpp"

namespace scatter::server {
namespace {

bool is_asset_id(const std::string& s) {
  return is_bake_key(s);
}

std::vector<double> numbers(const std::string& text, size_t count, const std::string& field) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw ValidationError(field, "\"" + item + "\" is not a number");
    }
  }
  if (v.size() != count)
    throw ValidationError(field, "needs " + std::to_string(count) + " comma-separated numbers");
  return v;
}

}  // namespace

void resolve_assets(nlohmann::json& j, const std::string& path, const std::filesystem::path& dir) {
  if (j.is_object()) {
    if (j.contains("asset")) {
      std::string p = path + ".asset";
      if (!j["asset"].is_string() || !is_asset_id(j["asset"].get<std::string>()))
        throw ValidationError(p, "must be an asset id (64 hex digits, from POST /api/assets)");
      if (j.contains("file")) throw ValidationError(p, "give \"asset\" or \"file\", not both");
      std::string id = j["asset"];
      std::filesystem::path file;
      for (const char* ext : {".obj", ".ply", ".stl", ".glb", ".off", ".grid.json"})
        if (!dir.empty() && std::filesystem::exists(dir / (id + ext))) file = dir / (id + ext);
      if (file.empty()) throw ValidationError(p, "no uploaded asset " + id);
      j.erase("asset");
      j["file"] = file.string();
    }
    for (auto& [key, value] : j.items()) resolve_assets(value, path + "." + key, dir);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i)
      resolve_assets(j[i], path + "[" + std::to_string(i) + "]", dir);
  }
}

HttpResponse Api::assets(const HttpRequest& request) {
  const auto& dir = options_.assets_dir;
  auto describe = [&](const std::filesystem::path& file) {
    std::string name = file.filename().string();
    std::string id = name.substr(0, 64);
    bool grid = name.size() > 64 && name.substr(64) == ".grid.json";
    nlohmann::json j = {{"id", id}, {"kind", grid ? "grid" : "mesh"}};
    std::error_code ec;
    j["bytes"] = std::filesystem::file_size(grid ? dir / (id + ".raw") : file, ec);
    if (!grid) j["format"] = file.extension().string().substr(1);
    return j;
  };
  if (request.method == "GET") {
    nlohmann::json list = nlohmann::json::array();
    std::error_code ec;
    if (!dir.empty())
      for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
        std::string name = e.path().filename().string();
        if (name.size() < 65 || !is_asset_id(name.substr(0, 64)) ||
            name.find(".tmp") != std::string::npos)
          continue;
        if (name.substr(64) == ".raw") continue;  // a grid's data, listed with its header
        list.push_back(describe(e.path()));
      }
    return json_response({{"assets", list}});
  }
  if (request.method != "POST")
    return error(405, request.method + " is not allowed on /api/assets: use POST or GET");
  if (dir.empty()) return error(503, "this server keeps no assets (start it with a --cache-dir)");
  auto q = parse_query(request.target);
  std::string kind = q.count("kind") ? q["kind"] : "mesh";
  if (kind != "mesh" && kind != "grid") throw ValidationError("kind", "must be mesh or grid");
  if (request.body.empty()) throw ValidationError("body", "is empty: send the file's bytes");
  // The folder and the files written into it are the server's: failing them is not the request's
  // fault (503), and the message names no server path.
  std::error_code made;
  std::filesystem::create_directories(dir, made);
  if (made || !std::filesystem::is_directory(dir))
    throw ServerUnavailable("body",
                            "the server cannot store uploads: its assets folder cannot be "
                            "created (" +
                                made.message() + ")");
  // Written under a temporary name, checked, then renamed: a bad upload leaves nothing behind.
  static std::atomic<unsigned> serial{0};
  std::string tmp = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(serial++);
  // Messages name "the upload", not the server's files.
  auto plain = [&](std::string m, const std::filesystem::path& p) {
    for (const std::string& s : {p.string(), p.filename().string()})
      for (size_t at; !s.empty() && (at = m.find(s)) != std::string::npos;)
        m.replace(at, s.size(), "the upload");
    return m;
  };
  auto write = [&](const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out)
      throw ServerUnavailable("body",
                              "the server cannot store the upload (its assets "
                              "folder is not writable or is full)");
  };
  nlohmann::json info;
  if (kind == "mesh") {
    std::string format = q.count("format") ? q["format"] : "";
    static const std::set<std::string> kFormats = {"obj", "ply", "stl", "glb", "off"};
    if (!kFormats.count(format))
      throw ValidationError("format", "must be one of obj, ply, stl, glb, off");
    const std::string id = sha256_hex(request.body);
    auto final_path = dir / (id + "." + format);
    if (std::filesystem::exists(final_path)) return json_response(describe(final_path), 200);
    auto tmp_path = dir / (id + tmp + "." + format);
    write(tmp_path, request.body);
    try {
      Mesh mesh = load_mesh(tmp_path);
      WatertightReport w = check_watertight(mesh);
      if (!w.watertight())
        throw ValidationError("body", "the mesh is not watertight (" + w.summary() + ")");
      Vec3 size = mesh.bounds().size();
      if (!(std::abs(mesh.volume()) > 1e-9 * size.x * size.y * size.z) ||
          std::max({size.x, size.y, size.z}) <= 0)
        throw ValidationError("body", "the mesh encloses no volume");
      info = {{"triangles", mesh.triangle_count()}};
    } catch (const ValidationError&) {
      std::filesystem::remove(tmp_path);
      throw;
    } catch (const std::exception& e) {
      std::filesystem::remove(tmp_path);
      throw ValidationError("body",
                            "is not a readable " + format + " mesh: " + plain(e.what(), tmp_path));
    }
    std::filesystem::rename(tmp_path, final_path);
    nlohmann::json j = describe(final_path);
    j.update(info);
    return json_response(j, 201);
  }
  if (!q.count("dims")) throw ValidationError("dims", "is required for a grid: nx,ny,nz");
  if (!q.count("bounds"))
    throw ValidationError("bounds", "is required for a grid: x0,y0,z0,x1,y1,z1");
  std::vector<double> d = numbers(q["dims"], 3, "dims"), b = numbers(q["bounds"], 6, "bounds");
  // A grid is its values and where they sit: both name it.
  const std::string id = sha256_hex(nlohmann::json({d, b}).dump() + "\n" + request.body);
  for (double v : d)
    if (v != std::floor(v) || v < 1 || v > 512)
      throw ValidationError("dims", "must be integers in [1, 512]");
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(b[a]) <= 1e6 && std::abs(b[a + 3]) <= 1e6 && b[a] < b[a + 3]))
      throw ValidationError("bounds",
                            "must be x0,y0,z0,x1,y1,z1 in [-1e6, 1e6] with x1 > x0, y1 > y0 and "
                            "z1 > z0");
  nlohmann::json header = {{"dims", {int(d[0]), int(d[1]), int(d[2])}},
                           {"format", "float32"},
                           {"data", id + ".raw"},
                           {"bounds", {{"min", {b[0], b[1], b[2]}}, {"max", {b[3], b[4], b[5]}}}}};
  auto final_header = dir / (id + ".grid.json");
  if (std::filesystem::exists(final_header)) return json_response(describe(final_header), 200);
  // Checked by the scene loader itself, from a temporary header next to the data.
  write(dir / (id + ".raw"), request.body);
  auto tmp_header = dir / (id + tmp + ".grid.json");
  write(tmp_header, header.dump());
  try {
    nlohmann::json density = {{"type", "grid"}, {"file", tmp_header.string()}};
    JsonObject o(density, "grid");
    parse_density(o, dir);
  } catch (const std::exception& e) {
    std::filesystem::remove(tmp_header);
    std::filesystem::remove(dir / (id + ".raw"));
    throw ValidationError(
        "body", "is not a valid grid: " + plain(plain(e.what(), tmp_header), dir / (id + ".raw")));
  }
  std::filesystem::rename(tmp_header, final_header);
  return json_response(describe(final_header), 201);
}

}  // namespace scatter::server
