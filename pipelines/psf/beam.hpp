// The spread of a collimated beam in an unbounded homogeneous medium (the paper's section 3.3 and
// figure 4): a Monte Carlo of Henyey-Greenstein scattering on the CPU tallies the weight of every
// scattering event whose incoming direction lies within `cone` of the beam's axis, binned by the
// distance along the axis and the transverse offset (both transverse axes pooled); the full width
// at half maximum of each distance bin's profile is compared with equation 18's width.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

namespace scatter::psf {

struct BeamParams {
  double b = 0.1;     // scattering coefficient (per unit length)
  double a = 0.0003;  // absorption coefficient
  double g = 0.9;
  double length = 200;  // the beam is followed to this distance along its axis
  int bins = 20;        // distance bins
  double cone = 0.2;    // radians: the events tallied travel within this angle of the axis
  long long photons = 1'000'000;
  uint32_t seed = 1;
  int threads = 0;  // 0: hardware concurrency
};

struct BeamRow {
  double distance = 0;    // the bin's centre
  double events = 0;      // tallied weight in the bin
  double fwhm_mc = 0;     // of the transverse profile; 0 when too few events
  double fwhm_model = 0;  // 2 sqrt(2 ln 2) w, w from equation 18 with the 8/b shift
  double fwhm_model_noshift = 0;
};

// Throws ValidationError for parameters out of range.
std::vector<BeamRow> beam_spread(const BeamParams& params);

void to_json(nlohmann::json& j, const BeamRow& r);

}  // namespace scatter::psf
