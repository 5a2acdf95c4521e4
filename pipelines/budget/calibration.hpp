// The calibration table: each approximate way of rendering a term's error against the reference
// (relative RMSE), and the reference path tracer's noise per sample, measured by
// `scatterd bench --calibrate` over calibration scenes that span the scene classes. Shipped as
// pipelines/budget/calibration.json (embedded in the binary; regenerate it with that command and
// bump its version when a pipeline's results change).
//
// A way is one pipeline at one of its qualities rendering the terms ("lbl:normal"), or for all
// terms the single term from one and the multiple term from another, summed
// ("thickness:normal+lbl:normal").
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pipelines/budget/scene_class.hpp"

namespace scatter {

struct WayPart {
  std::string pipeline, quality;
  Terms terms = Terms::All;
};

struct Way {
  std::vector<WayPart> parts;  // one, or two (single then multiple) for a composite
  std::string id() const;
  // Parses an id; `terms` are the terms the whole way renders. Throws std::invalid_argument.
  static Way parse(const std::string& id, Terms terms);
  // The quality's settings for each part (the pipeline's registry presets).
  Settings settings(size_t part) const;
};

// One calibration scene rendered for one terms.
struct CalibrationEntry {
  std::string scene;  // its name in the calibration set
  SceneClass cls;
  std::map<std::string, double> error;  // way id -> relative RMSE against the reference
  std::map<std::string, double> ms;     // way id -> frame milliseconds at the table's size
  // The reference path tracer's relative noise times sqrt(samples per pixel): its relative
  // standard error at n samples per pixel is noise / sqrt(n). 0 when not measured.
  double noise = 0;
  double reference_noise = 0;  // the noise of the reference these errors were measured against
  // The grid's scene this one is a twin of, lit from further round (SceneClass::facing); empty
  // for the grid's own, lit from the front.
  std::string twin;
};

class CalibrationTable {
 public:
  static constexpr int kFormat = 1;
  // pipelines/budget/calibration.json as embedded at build time.
  static const CalibrationTable& shipped();
  static CalibrationTable from_json(const nlohmann::json& j);
  nlohmann::json to_json() const;

  int version = 0;  // the table's own version: bumped whenever it is regenerated
  std::string command;
  int width = 0, height = 0;
  std::vector<CalibrationEntry> entries;

  // What the table says of `way` for a scene of class `c`, among the calibration scenes of the
  // same kind (terms, homogeneous, index matched) that measured it, lit from the front (the
  // most frontal facing among them): the worst error in the grid cell around the scene (per
  // feature, the calibrated values bracketing it; the two nearest where the cell holds none),
  // doubled when the scene lies outside the range they span. A scene lit from further round
  // (a facing below the front's) takes, per facing the twins are lit from, the ratio of a twin's
  // error to its grid scene's (the worst in the scene's cell, as for the errors), linear in the
  // facing between those facings (1 at the front), and doubled further round than the last; a
  // kind with no twins takes none (a table from before the facing). Nothing when no scene of
  // its kind measured the way.
  struct Prediction {
    double value = 0;
    bool inside = true;
    std::string note;  // "2 calibration scenes near it" or what lies outside the range
  };
  std::optional<Prediction> predict_error(const SceneClass& c, const std::string& way) const;
  // The reference's noise constant (see CalibrationEntry::noise) for the class, the same way
  // (the facing's ratio included; 1.5x when outside; past the calibrated g, the ratio of
  // phase_spread at g to that at the calibrated g nearest, to the power 1.5, where that is more:
  // measured on a 24 x 24 sphere the noise went x3.5 from g -0.7 to -0.9 and x5.2 from 0.7 to 0.9,
  // the spread x3.0).
  std::optional<Prediction> predict_noise(const SceneClass& c) const;
  // The ways calibrated for `terms`, in a stable order.
  std::vector<std::string> ways(Terms terms) const;
  // A scene's facing this close to the grid's counts as lit the same way.
  static constexpr double kFacingTolerance = 0.05;

 private:
  std::optional<Prediction> predict(const SceneClass& c, const std::string& what, bool noise,
                                    double outside_factor) const;
};

// sqrt(4 pi * integral of p^2) of the Henyey-Greenstein phase function at g: how much the path
// tracer's next-event estimates at each vertex vary, relative to isotropic scattering.
double phase_spread(double g);

}  // namespace scatter
