// A pipeline's settings as data: one row per key with its kind, range, what it shapes and one
// line of doc; the default is the typed struct's own member initialiser, so it is written once.
// The table fills the struct in one pass (SettingsReader: ranges, integers, unknown keys), builds
// the bake's and the kept states' keys from the rows that shape them, and describes itself for
// GET /api/pipelines, `scatterd pipelines` and docs/pipelines/.
//
//   const SettingsTable<LblSettings>& lbl_settings() {
//     static const SettingsTable<LblSettings> t("lbl", {
//         setting("rays", &LblSettings::rays, 0.25, 8, kept("lights"), "light rays per voxel
//         width"),
//         ...});
//     return t;
//   }
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bake/cache.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter {

enum class SettingKind { Number, Integer, Flag };
std::string to_string(SettingKind k);

// What a setting's value shapes: only the frame it renders, the cached bake product, or a state
// the pipeline keeps between frames (named, for pipelines that keep several).
struct Shapes {
  enum class What { Frame, Bake, Kept } what = What::Frame;
  std::string state;  // Kept: which state ("material", "lights", ...)
};
inline Shapes frame() {
  return {};
}
inline Shapes baked() {
  return {Shapes::What::Bake, "bake"};
}
inline Shapes kept(std::string state) {
  return {Shapes::What::Kept, std::move(state)};
}

struct SettingInfo {
  std::string key;
  SettingKind kind = SettingKind::Number;
  double def = 0, lo = 0, hi = 0;
  std::vector<double> allowed;  // when not empty, the only values accepted
  Shapes shapes;
  std::string doc;
};
void to_json(nlohmann::json& j, const SettingInfo& s);
// "frame", "bake" or "kept".
std::string to_string(Shapes::What w);

// Throws ValidationError("settings.<key>") unless v is one of `allowed` ("must be 6 or 18").
void check_allowed(const std::string& key, double v, const std::vector<double>& allowed);

template <class S>
class SettingsTable {
 public:
  struct Row {
    SettingInfo info;
    std::function<void(S&, double)> set;
    std::function<double(const S&)> get;
  };

  // `check` runs after the rows: rules across settings ("18 directions need blocked 0").
  SettingsTable(std::string pipeline, std::vector<Row> rows,
                std::function<void(const S&)> check = {})
      : pipeline_(std::move(pipeline)), rows_(std::move(rows)), check_(std::move(check)) {
    for (const Row& r : rows_) info_.push_back(r.info);
  }

  const std::string& pipeline() const { return pipeline_; }
  const std::vector<SettingInfo>& info() const { return info_; }

  // The struct from `settings`: every row's value or its default, checked against its kind and
  // range; a key no row holds is a ValidationError naming it.
  S read(const Settings& settings) const {
    SettingsReader r(settings, pipeline_);
    S s{};
    for (const Row& row : rows_) {
      const SettingInfo& i = row.info;
      double v = i.kind == SettingKind::Number ? r.number(i.key, i.def, i.lo, i.hi)
                                               : r.integer(i.key, int(i.def), int(i.lo), int(i.hi));
      if (!i.allowed.empty()) check_allowed(i.key, v, i.allowed);
      row.set(s, v);
    }
    r.finish();
    if (check_) check_(s);
    return s;
  }

  // Adds the value of every row that shapes `what` (and, for Kept, `state`) to `key`, by name.
  void add_to(BakeKey& key, const S& s, Shapes::What what, const std::string& state = {}) const {
    for (const Row& row : rows_)
      if (row.info.shapes.what == what && (state.empty() || row.info.shapes.state == state))
        key.add(row.info.key, row.get(s));
  }

 private:
  std::string pipeline_;
  std::vector<Row> rows_;
  std::vector<SettingInfo> info_;
  std::function<void(const S&)> check_;
};

namespace settings_detail {

template <class M>
constexpr SettingKind kind_of() {
  if constexpr (std::is_same_v<M, bool>)
    return SettingKind::Flag;
  else if constexpr (std::is_integral_v<M>)
    return SettingKind::Integer;
  else
    return SettingKind::Number;
}

template <class S, class M, class Access>
typename SettingsTable<S>::Row row(std::string key, Access access, double lo, double hi,
                                   Shapes shapes, std::string doc) {
  const S defaults{};
  SettingInfo info{std::move(key),    kind_of<M>(),  double(access(defaults)), lo, hi, {},
                   std::move(shapes), std::move(doc)};
  if (info.kind == SettingKind::Flag) info.lo = 0, info.hi = 1;
  auto set = [access](S& s, double v) {
    auto& m = const_cast<M&>(access(static_cast<const S&>(s)));
    if constexpr (std::is_same_v<M, bool>)
      m = v != 0;
    else
      m = static_cast<M>(v);
  };
  auto get = [access](const S& s) { return double(access(s)); };
  return {std::move(info), set, get};
}

}  // namespace settings_detail

// A row for member `m` of S (default: S{}.*m). The member's type gives the kind: bool a flag
// (0 or 1), an integer type an integer, a floating type a number.
template <class S, class M>
typename SettingsTable<S>::Row setting(std::string key, M S::*m, double lo, double hi,
                                       Shapes shapes, std::string doc) {
  return settings_detail::row<S, M>(
      std::move(key), [m](const S& s) -> const M& { return s.*m; }, lo, hi, std::move(shapes),
      std::move(doc));
}

// A row for member `m` of the nested struct `outer` of S.
template <class S, class O, class M>
typename SettingsTable<S>::Row setting(std::string key, O S::*outer, M O::*m, double lo, double hi,
                                       Shapes shapes, std::string doc) {
  return settings_detail::row<S, M>(
      std::move(key), [outer, m](const S& s) -> const M& { return (s.*outer).*m; }, lo, hi,
      std::move(shapes), std::move(doc));
}

// A flag row (range [0, 1]).
template <class S>
typename SettingsTable<S>::Row flag(std::string key, bool S::*m, Shapes shapes, std::string doc) {
  return setting(std::move(key), m, 0, 1, std::move(shapes), std::move(doc));
}

// A row whose value must also be one of `allowed`.
template <class Row>
Row one_of(Row row, std::vector<double> allowed) {
  row.info.allowed = std::move(allowed);
  return row;
}

}  // namespace scatter
