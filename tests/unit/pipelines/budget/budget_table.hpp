// The hand-made calibration table of the budget planner's tests: two homogeneous scenes per
// terms, at tau 2 and 8.
#pragma once

#include <map>
#include <string>

#include "pipelines/budget/calibration.hpp"

namespace scatter::test {

inline CalibrationEntry entry(const std::string& name, Terms terms, double albedo, double tau,
                              std::map<std::string, double> error, double noise = 0) {
  CalibrationEntry e;
  e.scene = name;
  e.cls.terms = terms;
  e.cls.albedo = albedo;
  e.cls.tau = tau;
  e.error = std::move(error);
  e.noise = noise;
  return e;
}

inline CalibrationTable table() {
  CalibrationTable t;
  t.version = 1;
  t.width = t.height = 64;
  t.entries = {
      entry("thin", Terms::Single, 0.9, 2, {{"thickness:normal", 0.02}, {"single:normal", 0.04}}),
      entry("thick", Terms::Single, 0.9, 8, {{"thickness:normal", 0.03}, {"single:normal", 0.05}}),
      entry("thin", Terms::All, 0.9, 2,
            {{"lbl:normal", 0.04}, {"psf:normal", 0.30}, {"thickness:normal+lbl:normal", 0.06}},
            0.8),
      entry("thick", Terms::All, 0.9, 8,
            {{"lbl:normal", 0.08}, {"psf:normal", 0.40}, {"thickness:normal+lbl:normal", 0.09}},
            1.6),
  };
  return t;
}

}  // namespace scatter::test
