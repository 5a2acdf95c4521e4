#include "pipelines/budget/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
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
    c.twin = e.value("twin", "");
    t.entries.push_back(std::move(c));
  }
  return t;
}

nlohmann::json CalibrationTable::to_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const CalibrationEntry& e : entries) {
    rows.push_back({{"scene", e.scene},
                    {"class", e.cls},
                    {"error", e.error},
                    {"ms", e.ms},
                    {"noise", e.noise},
                    {"reference_noise", e.reference_noise}});
    if (!e.twin.empty()) rows.back()["twin"] = e.twin;
  }
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

namespace {

// A calibrated value at a class's features.
struct Point {
  const CalibrationEntry* entry;
  double value;
};

struct Cell {
  double value = 0;
  std::string note;
};

using ValueOf = std::function<std::optional<double>(const CalibrationEntry&)>;

// The calibration grid's cell around `c`: per feature, the nearest calibrated values at or below
// and at or above it. The worst of the points in that cell (the error need not be monotone in any
// one feature, but is bounded by its corners better than by its nearest neighbour); with none
// there, the worse of the two nearest. `points` is not empty.
Cell worst_in_cell(std::vector<Point> points, const SceneClass& c) {
  auto distance = [&](const Point& p) {
    double d2 = 0;
    for (int i = 0; i < SceneClass::kFeatures; ++i)
      d2 += std::pow(p.entry->cls.feature(i) - c.feature(i), 2);
    return d2;
  };
  std::sort(points.begin(), points.end(),
            [&](const Point& a, const Point& b) { return distance(a) < distance(b); });
  double below[SceneClass::kFeatures], above[SceneClass::kFeatures];
  for (int i = 0; i < SceneClass::kFeatures; ++i) {
    below[i] = -1e300;
    above[i] = 1e300;
    for (const Point& n : points) {
      double f = n.entry->cls.feature(i), x = c.feature(i);
      if (f <= x + 1e-9) below[i] = std::max(below[i], f);
      if (f >= x - 1e-9) above[i] = std::min(above[i], f);
    }
  }
  Cell cell;
  int in_cell = 0;
  for (const Point& n : points) {
    bool inside = true;
    for (int i = 0; i < SceneClass::kFeatures; ++i) {
      double f = n.entry->cls.feature(i);
      inside = inside && f >= below[i] - 1e-9 && f <= above[i] + 1e-9;
    }
    if (!inside) continue;
    if (n.value >= cell.value) cell.note = "the worst of its calibration cell: " + n.entry->scene;
    cell.value = std::max(cell.value, n.value);
    ++in_cell;
  }
  if (in_cell == 0) {
    size_t k = std::min<size_t>(2, points.size());
    for (size_t i = 0; i < k; ++i) cell.value = std::max(cell.value, points[i].value);
    cell.note = "from " + points[0].entry->scene + (k > 1 ? " and " + points[1].entry->scene : "");
  }
  return cell;
}

// How much the error grows, for a scene lit from further round than the calibration grid (its
// facing under `front`), from the grid scenes to their twins lit from there (`value_of`: what an
// entry of the scene's kind measured); 1 with no note where no twin says, `inside` false where the
// scene lies past what the twins measured.
struct Lighting {
  double ratio = 1;
  std::string note;
  bool inside = true;
};

Lighting lighting_factor(const std::vector<CalibrationEntry>& entries, const SceneClass& c,
                         double front, const ValueOf& value_of, bool noise, double outside_factor) {
  constexpr double kFacingTolerance = CalibrationTable::kFacingTolerance;
  auto is_front = [](const CalibrationEntry& e) { return e.twin.empty(); };
  // Lit from further round than the grid: the front prediction times how much the error grew
  // from a grid scene to its twin lit from there (the same class but the facing). Per facing
  // the calibration lights from, the ratio at the scene's class is the worst in its cell of the
  // twins' ratios (as the grid's errors are, worst_in_cell), its excess over 1 doubled where
  // the scene's tau or g lies outside the twins' (the ratios grow with both: x1.0 at tau 1 to
  // x4.8 at 16 for psf behind; with albedo they change by under a tenth); between those facings
  // linear, from 1 at the front; never less than at a facing nearer the front.
  struct Level {
    double facing;
    std::vector<Point> ratios;
    Cell at;
  };
  std::vector<Level> levels;
  bool kind_has_twins = false;
  // Below a tenth of a percent an error's ratio says nothing (the marcher's 0 at both).
  const double floor = noise ? 0.0 : 1e-3;
  for (const CalibrationEntry& lit : entries) {
    if (is_front(lit) || lit.cls.terms != c.terms || lit.cls.homogeneous != c.homogeneous ||
        lit.cls.index_matched != c.index_matched)
      continue;
    kind_has_twins = true;
    auto v = value_of(lit);
    // A twin lit from the grid's side of the front is no twin (a hand-made table's).
    if (!v || lit.cls.facing >= front - kFacingTolerance) continue;
    for (const CalibrationEntry& twin : entries) {
      // Its name first: the way's error is looked up for the one twin only.
      if (twin.scene != lit.twin || twin.cls.terms != lit.cls.terms || !is_front(twin)) continue;
      auto b = value_of(twin);
      if (!b || *b + floor <= 0) continue;
      const double ratio = std::max(1.0, (*v + floor) / (*b + floor));
      auto level = std::find_if(levels.begin(), levels.end(), [&](const Level& l) {
        return std::abs(l.facing - lit.cls.facing) < 0.1;
      });
      if (level == levels.end()) {
        levels.push_back(Level{lit.cls.facing, {}, {}});
        level = levels.end() - 1;
      }
      level->ratios.push_back({&lit, ratio});
      break;
    }
  }
  std::string note;
  double ratio = 1;
  bool inside = true;
  if (!levels.empty()) {
    std::sort(levels.begin(), levels.end(),
              [](const Level& a, const Level& b) { return a.facing > b.facing; });
    levels.insert(levels.begin(), Level{front, {}, Cell{1.0, "the front"}});
    for (size_t i = 1; i < levels.size(); ++i) {
      Level& l = levels[i];
      l.at = worst_in_cell(l.ratios, c);
      std::string past;
      for (int f : {0, 2}) {
        double lo_f = 1e300, hi_f = -1e300;
        for (const Point& r : l.ratios) {
          lo_f = std::min(lo_f, r.entry->cls.feature(f));
          hi_f = std::max(hi_f, r.entry->cls.feature(f));
        }
        if (c.feature(f) < lo_f - 0.05 || c.feature(f) > hi_f + 0.05)
          past += std::string(past.empty() ? "" : " and ") + SceneClass::feature_name(f);
      }
      if (!past.empty()) {
        l.at.value = 1 + (l.at.value - 1) * outside_factor;
        l.at.note += ", its excess doubled: " + past + " outside its twins'";
      }
      if (levels[i - 1].at.value > l.at.value) l.at = levels[i - 1].at;
    }
    const Level& last = levels.back();
    ratio = last.at.value;
    std::string from = last.at.note;
    for (size_t i = 1; i < levels.size(); ++i)
      if (c.facing >= levels[i].facing) {
        const Level &a = levels[i - 1], &b = levels[i];
        ratio =
            b.at.value + (a.at.value - b.at.value) * (c.facing - b.facing) / (a.facing - b.facing);
        from = b.at.note;
        break;
      }
    note = "lit from facing " + short_number(c.facing) + ", the calibration's " +
           short_number(front) + ": x" + short_number(ratio) +
           " (its twins lit from further round: " + from + ")";
    if (c.facing < last.facing - kFacingTolerance) {
      ratio *= outside_factor;
      inside = false;
      note +=
          ", further round than calibrated (x" + short_number(outside_factor) + ", conservative)";
    }
  } else if (kind_has_twins) {
    // Twins of its kind were lit from further round, but none measured this: no evidence
    // that it holds up there.
    ratio = outside_factor;
    inside = false;
    note = "lit from facing " + short_number(c.facing) + ", the calibration's " +
           short_number(front) + ": no twin lit from further round measured it (x" +
           short_number(outside_factor) + ", conservative)";
  }
  return {ratio, note, inside};
}

}  // namespace

std::optional<CalibrationTable::Prediction> CalibrationTable::predict(const SceneClass& c,
                                                                      const std::string& what,
                                                                      bool noise,
                                                                      double outside_factor) const {
  // What an entry of the scene's kind (terms, homogeneous, index matched) measured of `what`.
  auto value_of = [&](const CalibrationEntry& e) -> std::optional<double> {
    if (e.cls.terms != c.terms || e.cls.homogeneous != c.homogeneous ||
        e.cls.index_matched != c.index_matched)
      return std::nullopt;
    if (noise) return e.noise > 0 ? std::optional<double>(e.noise) : std::nullopt;
    auto it = e.error.find(what);
    return it == e.error.end() ? std::nullopt : std::optional<double>(it->second);
  };
  // The grid: the entries lit as the calibration lights them (no twin), from `front`, the most
  // frontal facing among them. The others are twins of grid entries lit from further round.
  double front = -2;
  for (const CalibrationEntry& e : entries)
    if (e.twin.empty() && value_of(e)) front = std::max(front, e.cls.facing);
  auto is_front = [](const CalibrationEntry& e) { return e.twin.empty(); };
  std::vector<Point> grid;
  double lo[SceneClass::kFeatures], hi[SceneClass::kFeatures];
  std::fill(lo, lo + SceneClass::kFeatures, 1e300);
  std::fill(hi, hi + SceneClass::kFeatures, -1e300);
  for (const CalibrationEntry& e : entries) {
    auto v = value_of(e);
    if (!v || !is_front(e)) continue;
    for (int i = 0; i < SceneClass::kFeatures; ++i) {
      lo[i] = std::min(lo[i], e.cls.feature(i));
      hi[i] = std::max(hi[i], e.cls.feature(i));
    }
    grid.push_back({&e, *v});
  }
  if (grid.empty()) return std::nullopt;
  Prediction p;
  {
    Cell cell = worst_in_cell(grid, c);
    p.value = cell.value;
    p.note = cell.note;
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
  if (c.facing < front - kFacingTolerance) {
    Lighting lit = lighting_factor(entries, c, front, value_of, noise, outside_factor);
    p.inside = p.inside && lit.inside;
    if (!lit.note.empty()) {
      p.value *= lit.ratio;
      p.note = lit.note + "; " + p.note;
    }
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
