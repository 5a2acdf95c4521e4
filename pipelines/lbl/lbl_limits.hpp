// The range of g over which lbl's multiple term was measured within 10 % on all terms
// (docs/BENCHMARKS.md, lbl: the sphere at g 0.9 9 %, at g -0.3 8 %, at g -0.7 35 %). The budget
// planner does not send the multiple term of media outside it to lbl, and lbl's plan says where
// that term is least accurate.
#pragma once

namespace scatter::lbl {

constexpr double kMultipleMeasuredMaxG = 0.9;  // nothing sharper measured
constexpr double kMultipleMeasuredMinG = -0.3;

// The setting `gathers` (the scattering orders computed exactly after the first) at most, the
// slab's too (pipelines/lbl/slab.hpp).
constexpr int kMaxGathers = 8;

// The setting `lobes` at most, and what the lights' own deposits may take on the device
// (pipelines/lbl/lbl_frame.cpp, light_lobes).
constexpr int kMaxLobes = 64;
constexpr double kMaxLobeBytes = 512.0 * 1024 * 1024;

}  // namespace scatter::lbl
