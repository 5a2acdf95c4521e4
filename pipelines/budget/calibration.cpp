#include "pipelines/budget/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "gpu/embedded_sources.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

std::string Way::id() const {
  std::string s;
  for (const WayPart& p : parts) s += (s.empty() ? "" : "+") + p.pipeline + ":" + p.quality;
  return s;
}

Way Way::parse(const std::string& id, Terms terms) {
  Way w;
  size_t start = 0;
  while (start <= id.size()) {
    size_t plus = id.find('+', start);
    std::string item =
        id.substr(start, plus == std::string::npos ? std::string::npos : plus - start);
    size_t colon = item.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == item.size())
      throw std::invalid_argument("way \"" + id +
                                  "\": expected pipeline:quality[+pipeline:quality]");
    w.parts.push_back({item.substr(0, colon), item.substr(colon + 1), terms});
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  if (w.parts.size() > 2) throw std::invalid_argument("way \"" + id + "\": at most two parts");
  if (w.parts.size() == 2) {
    if (terms != Terms::All)
      throw std::invalid_argument("way \"" + id + "\": a composite renders all terms");
    w.parts[0].terms = Terms::Single;
    w.parts[1].terms = Terms::Multiple;
  }
  return w;
}

Settings Way::settings(size_t part) const {
  const WayPart& p = parts.at(part);
  for (const Quality& q : pipeline_info(p.pipeline).qualities)
    if (q.name == p.quality) return q.settings;
  throw std::invalid_argument("pipeline " + p.pipeline + " has no quality " + p.quality);
}

const CalibrationTable& CalibrationTable::shipped() {
  static const CalibrationTable table = [] {
    const auto& files = gpu::embedded_sources();
    auto it = files.find("pipelines/budget/calibration.json");
    if (it == files.end()) return CalibrationTable{};
    return from_json(nlohmann::json::parse(it->second));
  }();
  return table;
}

CalibrationTable CalibrationTable::from_json(const nlohmann::json& j) {
  if (j.at("format").get<int>() != kFormat)
    throw std::invalid_argument("calibration table format " + j.at("format").dump() +
                                ", this build reads " + std::to_string(kFormat));
  CalibrationTable t;
  t.version = j.at("version").get<int>();
  t.command = j.value("command", "");
  t.width = j.at("width").get<int>();
  t.height = j.at("height").get<int>();
  for (const auto& e : j.at("entries")) {
    CalibrationEntry c;
    c.scene = e.at("scene").get<std::string>();
    c.cls = e.at("class").get<SceneClass>();
    c.error = e.at("error").get<std::map<std::string, double>>();
    c.ms = e.value("ms", std::map<std::string, double>{});
    c.noise = e.value("noise", 0.0);
    c.reference_noise = e.value("reference_noise", 0.0);
    t.entries.push_back(std::move(c));
  }
  return t;
}

nlohmann::json CalibrationTable::to_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const CalibrationEntry& e : entries)
    rows.push_back({{"scene", e.scene},
                    {"class", e.cls},
                    {"error", e.error},
                    {"ms", e.ms},
                    {"noise", e.noise},
                    {"reference_noise", e.reference_noise}});
  return {{"format", kFormat}, {"version", version}, {"command", command},
          {"width", width},    {"height", height},   {"entries", rows}};
}

std::vector<std::string> CalibrationTable::ways(Terms terms) const {
  std::set<std::string> seen;
  for (const CalibrationEntry& e : entries)
    if (e.cls.terms == terms)
      for (const auto& [way, err] : e.error) seen.insert(way);
  return {seen.begin(), seen.end()};
}

std::optional<CalibrationTable::Prediction> CalibrationTable::predict(const SceneClass& c,
                                                                      const std::string& what,
                                                                      bool noise,
                                                                      double outside_factor) const {
  struct Near {
    double distance, value;
    const CalibrationEntry* entry;
  };
  std::vector<Near> near;
  double lo[SceneClass::kFeatures], hi[SceneClass::kFeatures];
  std::fill(lo, lo + SceneClass::kFeatures, 1e300);
  std::fill(hi, hi + SceneClass::kFeatures, -1e300);
  for (const CalibrationEntry& e : entries) {
    if (e.cls.terms != c.terms || e.cls.homogeneous != c.homogeneous ||
        e.cls.index_matched != c.index_matched)
      continue;
    double value;
    if (noise) {
      if (e.noise <= 0) continue;
      value = e.noise;
    } else {
      auto it = e.error.find(what);
      if (it == e.error.end()) continue;
      value = it->second;
    }
    double d2 = 0;
    for (int i = 0; i < SceneClass::kFeatures; ++i) {
      double f = e.cls.feature(i);
      d2 += (f - c.feature(i)) * (f - c.feature(i));
      lo[i] = std::min(lo[i], f);
      hi[i] = std::max(hi[i], f);
    }
    near.push_back({std::sqrt(d2), value, &e});
  }
  if (near.empty()) return std::nullopt;
  std::sort(near.begin(), near.end(),
            [](const Near& a, const Near& b) { return a.distance < b.distance; });
  Prediction p;
  // The calibration grid's cell around the scene: per feature, the nearest calibrated values at
  // or below and at or above it. The prediction is the worst of the scenes in that cell (the
  // error need not be monotone in any one feature, but is bounded by its corners better than by
  // its nearest neighbour); with none there, the worse of the two nearest.
  double below[SceneClass::kFeatures], above[SceneClass::kFeatures];
  for (int i = 0; i < SceneClass::kFeatures; ++i) {
    below[i] = -1e300;
    above[i] = 1e300;
    for (const Near& n : near) {
      double f = n.entry->cls.feature(i), x = c.feature(i);
      if (f <= x + 1e-9) below[i] = std::max(below[i], f);
      if (f >= x - 1e-9) above[i] = std::min(above[i], f);
    }
  }
  int in_cell = 0;
  for (const Near& n : near) {
    bool inside = true;
    for (int i = 0; i < SceneClass::kFeatures; ++i) {
      double f = n.entry->cls.feature(i);
      inside = inside && f >= below[i] - 1e-9 && f <= above[i] + 1e-9;
    }
    if (!inside) continue;
    if (n.value >= p.value) p.note = "the worst of its calibration cell: " + n.entry->scene;
    p.value = std::max(p.value, n.value);
    ++in_cell;
  }
  if (in_cell == 0) {
    size_t k = std::min<size_t>(2, near.size());
    for (size_t i = 0; i < k; ++i) p.value = std::max(p.value, near[i].value);
    p.note = "from " + near[0].entry->scene + (k > 1 ? " and " + near[1].entry->scene : "");
  }
  std::string outside;
  double spread = 1;      // the noise's growth past the calibrated g
  bool flat_too = false;  // a feature other than the noise's g outside
  for (int i = 0; i < SceneClass::kFeatures; ++i) {
    double f = c.feature(i);
    if (f < lo[i] - 0.05 || f > hi[i] + 0.05) {
      outside += std::string(outside.empty() ? "" : ", ") + SceneClass::feature_name(i) + " " +
                 short_number(i == 0 ? c.tau : (i == 1 ? c.albedo : c.g)) +
                 " outside the calibrated range";
      if (noise && i == 2) {
        // The path tracer's noise past the calibrated g grows with the phase function's spread
        // (phase_spread): its ratio to the spread at the calibrated g nearest, to the power
        // 1.5 (conservative: from g 0 to -0.7 the table's noise grows 1.6-2.4x, the spread's
        // ratio 2.39 to that power 3.7x), where that is more than the flat factor.
        const double edge = std::clamp(f, lo[i], hi[i]) * SceneClass::kGStep;
        spread = std::pow(phase_spread(c.g) / phase_spread(edge), 1.5);
      } else {
        flat_too = true;
      }
    }
  }
  // The flat factor once, or the spread's where larger; both where another feature lies outside
  // as well.
  const double factor =
      spread > outside_factor ? spread * (flat_too ? outside_factor : 1.0) : outside_factor;
  if (!outside.empty()) {
    p.inside = false;
    p.value *= factor;
    p.note = outside + " (x" + short_number(factor) + ", conservative); " + p.note;
  }
  return p;
}

double phase_spread(double g) {
  // 4 pi times the integral of the Henyey-Greenstein phase function squared over the sphere is
  // (1 + g^2) / (1 - g^2)^2; its square root: 1 at g 0, 2.39 at |g| 0.7, 7.08 at 0.9, 70.7 at
  // 0.99.
  const double g2 = std::min(g * g, 0.9999);
  return std::sqrt(1 + g2) / (1 - g2);
}

std::optional<CalibrationTable::Prediction> CalibrationTable::predict_error(
    const SceneClass& c, const std::string& way) const {
  return predict(c, way, false, 2.0);
}

std::optional<CalibrationTable::Prediction> CalibrationTable::predict_noise(
    const SceneClass& c) const {
  return predict(c, "", true, 1.5);
}

}  // namespace scatter
