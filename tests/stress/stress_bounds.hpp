// What the stress suite holds every image to: finite, non-negative radiance, and where a
// physical upper bound on the radiance is known, at most that bound (derivations in
// stress_bounds.cpp and docs/STRESS.md).
#pragma once

#include <optional>
#include <string>

#include "pipelines/image.hpp"
#include "scene/scene.hpp"

namespace scatter::stress {

// "" when every value of `image` is finite and >= 0, else the first pixel that is not.
std::string bad_value(const Image& image);

// Henyey-Greenstein's phase function at cosine `mu`, and its maximum over all angles.
double hg(double mu, double g);
double hg_max(double g);

// A per-pixel upper bound on the single-scattered radiance of `scene` seen by its camera, or
// nothing where the suite knows none (a dielectric boundary focuses light; a light in the
// medium has unbounded irradiance near it). `isotropic_view`: the pipeline's view pass takes the
// phase as isotropic (lbl, as its plan says), so its model's phase is 1/(4 pi).
std::optional<Image> single_bound(const Scene& scene, bool isotropic_view);

// A per-pixel upper bound on the Blinn-Phong surface term (pipelines/surface), or nothing when a
// light touches the object.
std::optional<Image> surface_bound(const Scene& scene);

// "" when image <= bound everywhere (up to float32 rounding), else the worst pixel.
std::string above_bound(const Image& image, const Image& bound);

}  // namespace scatter::stress
