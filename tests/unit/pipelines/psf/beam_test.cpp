// The beam-spread Monte Carlo behind `scatterd beam`: widths grow along the beam, and a
// narrow-angle medium keeps the beam narrower than an isotropic one.
#include "pipelines/psf/beam.hpp"

#include <gtest/gtest.h>

#include "protocol/json_reader.hpp"

namespace scatter::psf {
namespace {

TEST(PsfBeam, WidthGrowsAlongTheBeamAndWithTheScatteringAngle) {
  BeamParams p;
  p.b = 0.2;
  p.length = 100;
  p.bins = 5;
  p.photons = 40000;
  p.threads = 2;
  auto forward = beam_spread(p);
  ASSERT_EQ(forward.size(), 5u);
  for (size_t i = 1; i < forward.size(); ++i) {
    EXPECT_GT(forward[i].fwhm_mc, forward[i - 1].fwhm_mc) << i;
    EXPECT_GE(forward[i].fwhm_model, forward[i - 1].fwhm_model) << i;
    EXPECT_LT(forward[i].events, forward[i - 1].events) << i;  // fewer events stay near the axis
  }
  p.g = 0.5;
  auto wide = beam_spread(p);
  EXPECT_GT(wide[2].fwhm_mc, forward[2].fwhm_mc);
  EXPECT_GT(wide[2].fwhm_model_noshift, forward[2].fwhm_model_noshift);
}

TEST(PsfBeam, RejectsBadParameters) {
  BeamParams p;
  p.b = 0;
  EXPECT_THROW(beam_spread(p), ValidationError);
  p = {};
  p.g = 1;
  EXPECT_THROW(beam_spread(p), ValidationError);
  p = {};
  p.bins = 0;
  EXPECT_THROW(beam_spread(p), ValidationError);
}

}  // namespace
}  // namespace scatter::psf
