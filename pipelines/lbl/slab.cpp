#include "pipelines/lbl/slab.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "pipelines/lbl/escape.hpp"
#include "pipelines/lbl/lattice.hpp"
#include "pipelines/lbl/second.hpp"

namespace scatter::lbl {
namespace {

constexpr double kPi = std::numbers::pi;

void check(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw ValidationError(field, problem);
}

double hg(double cos_theta, double g) {
  double d = 1 + g * g - 2 * g * cos_theta;
  return (1 - g * g) / (4 * kPi * d * std::sqrt(d));
}

// The midpoints of `n` equal pieces of (0, 1) in u, mapped by mu = u^2 (denser at grazing
// angles, where exp(-tau / mu) turns), with their weights d mu.
std::vector<std::pair<double, double>> mu_nodes(int n) {
  std::vector<std::pair<double, double>> nodes;
  for (int i = 0; i < n; ++i) {
    double u = (i + 0.5) / n;
    nodes.push_back({u * u, 2 * u / n});
  }
  return nodes;
}

// The HG phase about a direction at cosine mu0 to the normal, travelling into the slab (+z),
// summed over the azimuth at each of mu_nodes(n): `up` for light going back towards the lit face
// at cosine mu, `down` for light going on.
struct PhaseNodes {
  std::vector<std::pair<double, double>> nodes;
  std::vector<double> up, down;
};
PhaseNodes phase_nodes(double mu0, double g, int n) {
  PhaseNodes p{mu_nodes(n), {}, {}};
  const double sin0 = std::sqrt(std::max(0.0, 1 - mu0 * mu0));
  const int azimuths = 256;
  for (auto [mu, dmu] : p.nodes) {
    if (sin0 == 0) {  // about the normal: the same at every azimuth
      p.up.push_back(2 * kPi * hg(-mu0 * mu, g));
      p.down.push_back(2 * kPi * hg(mu0 * mu, g));
      continue;
    }
    double sin1 = std::sqrt(std::max(0.0, 1 - mu * mu)), up = 0, down = 0;
    for (int j = 0; j < azimuths; ++j) {
      double c = std::cos(kPi * (j + 0.5) / azimuths);
      up += hg(sin0 * sin1 * c - mu0 * mu, g);
      down += hg(sin0 * sin1 * c + mu0 * mu, g);
    }
    p.up.push_back(up * 2 * kPi / azimuths);
    p.down.push_back(down * 2 * kPi / azimuths);
  }
  return p;
}
// The chances that light emitted evenly over layer k (of `layers`, each of optical thickness d)
// by the phase `p` leaves through the lit face (first) and the other (second) without another
// interaction: per direction the phase times the layer's mean transmittance to the face. For
// isotropic emission (phase_nodes(1, 0, n): 1/2 each way) that is (1 / 2 d) integral over the
// layer of E2(t) dt, with int E2 = (1 / 2) int_0^1 mu (exp(-t0 / mu) - exp(-t1 / mu)) d mu.
std::pair<double, double> layer_escape_phase(int k, int layers, double d, const PhaseNodes& p) {
  double up = 0, down = 0;
  double t0 = k * d, t1 = (k + 1) * d, b0 = (layers - 1 - k) * d, b1 = (layers - k) * d;
  for (size_t i = 0; i < p.nodes.size(); ++i) {
    auto [mu, dmu] = p.nodes[i];
    up += p.up[i] * mu * (std::exp(-t0 / mu) - std::exp(-t1 / mu)) * dmu;
    down += p.down[i] * mu * (std::exp(-b0 / mu) - std::exp(-b1 / mu)) * dmu;
  }
  return {up / d, down / d};
}

// The chance that light emitted isotropically and evenly over a layer of optical thickness d
// reaches a plane D beyond the layer's near face (either way: half the directions), without a
// collision: (1 / 2 d) integral_0^1 mu (exp(-D / mu) - exp(-(D + d) / mu)) d mu.
double layer_reach(double D, double d, const std::vector<std::pair<double, double>>& nodes) {
  double sum = 0;
  for (auto [mu, dmu] : nodes) sum += mu * (std::exp(-D / mu) - std::exp(-(D + d) / mu)) * dmu;
  return sum / (2 * d);
}

// The second scattering exactly (the pipeline's setting `second`): what the light `first` emits
// isotropically per layer (uniform layers of optical thickness d, albedo a) scatters next, per
// layer: a times the chance to collide in each layer, a convolution over the layers' distance.
std::vector<float> slab_second(const std::vector<float>& first, int layers, double d, double a,
                               const std::vector<std::pair<double, double>>& nodes) {
  // kernel[m]: from a layer into one m layers away (either side); 0: its own.
  std::vector<double> kernel{1 - 2 * layer_reach(0, d, nodes)};
  for (int m = 1; m < layers; ++m) {
    double k = layer_reach((m - 1) * d, d, nodes) - layer_reach(m * d, d, nodes);
    kernel.push_back(k);
    if (k < 1e-12) break;
  }
  std::vector<float> second(first.size(), 0.f);
  const int reach = static_cast<int>(kernel.size());
  for (int k = 0; k < layers; ++k)
    for (int ch = 0; ch < 3; ++ch) {
      double sum = 0;
      for (int j = std::max(0, k - reach + 1); j < std::min(layers, k + reach); ++j)
        sum += kernel[std::abs(k - j)] * first[3 * j + ch];
      second[3 * k + ch] = static_cast<float>(a * sum);
    }
  return second;
}

// The next order's events per layer in the real medium (uniform layers of optical thickness d,
// albedo a): the light `emitted` per layer (scattered power) with each layer's phase (`ph`: HG
// summed over the azimuth per node, going up and down), colliding in each layer, times a; `mean`:
// the mean cosine (to +z) of the light arriving at those events (net over total).
std::vector<double> slab_next_order(const std::vector<double>& emitted,
                                    const std::vector<PhaseNodes>& ph, double d, double a,
                                    std::vector<double>& mean) {
  const int layers = static_cast<int>(emitted.size());
  std::vector<double> next(layers, 0), nextm(layers, 0);
  const auto& nodes = ph[0].nodes;
  for (int j = 0; j < layers; ++j) {
    if (!(emitted[j] > 0)) continue;
    for (size_t i = 0; i < nodes.size(); ++i) {
      auto [mu, dmu] = nodes[i];
      double wd = ph[j].down[i] * dmu * emitted[j], wu = ph[j].up[i] * dmu * emitted[j];
      auto reach = [&](double D) { return mu * (std::exp(-D / mu) - std::exp(-(D + d) / mu)) / d; };
      double self = 1 - reach(0);
      next[j] += (wd + wu) * self;
      nextm[j] += (wd - wu) * self * mu;
      double prev = reach(0);
      for (int m = 1; m < layers; ++m) {
        double cur = reach(m * d), c = prev - cur;
        prev = cur;
        if (c < 1e-14) break;
        if (j + m < layers) next[j + m] += wd * c, nextm[j + m] += wd * c * mu;
        if (j - m >= 0) next[j - m] += wu * c, nextm[j - m] -= wu * c * mu;
      }
    }
  }
  mean.assign(layers, 0);
  for (int k = 0; k < layers; ++k) {
    mean[k] = next[k] > 0 ? nextm[k] / next[k] : 0;
    next[k] *= a;
  }
  return next;
}

// The next order on layers `factor` times as thick (the pipeline's coarse gathers, setting
// `gathers`): the power per layer `q` summed per group of `factor` layers (a whole number of
// groups), the next order's events per group by slab_second, and per layer its group's share,
// linear between the groups' centres (the pipeline's trilinear fluence: sigma_s' is the same in
// every layer here).
std::vector<float> slab_next_coarse(const std::vector<float>& q, int layers, int factor, double d,
                                    double a, const std::vector<std::pair<double, double>>& nodes) {
  const int groups = layers / factor;
  std::vector<float> coarse(3 * size_t(groups), 0.f);
  for (int k = 0; k < groups * factor; ++k)
    for (int ch = 0; ch < 3; ++ch) coarse[3 * (k / factor) + ch] += q[3 * k + ch];
  std::vector<float> next_coarse = slab_second(coarse, groups, factor * d, a, nodes);
  std::vector<float> next(q.size());
  for (int k = 0; k < layers; ++k) {
    double u = std::clamp((k + 0.5) / factor - 0.5, 0.0, double(groups - 1));
    int c0 = std::min(static_cast<int>(u), groups - 1), c1 = std::min(c0 + 1, groups - 1);
    double f = u - c0;
    for (int ch = 0; ch < 3; ++ch)
      next[3 * k + ch] = static_cast<float>(
          ((1 - f) * next_coarse[3 * c0 + ch] + f * next_coarse[3 * c1 + ch]) / factor);
  }
  return next;
}

// HG(g |m|) about +z or -z (the sign of m), azimuth summed, on `n` nodes.
PhaseNodes axis_phase(double g, double m, int n) {
  PhaseNodes ph = phase_nodes(1.0, g * std::min(1.0, std::abs(m)), n);
  if (m < 0) std::swap(ph.up, ph.down);
  return ph;
}

}  // namespace

SingleScattering slab_single_scattering(const SlabParams& p) {
  // A beam of unit power per unit area enters at cosine mu0 and scatters at optical depth t with
  // density a exp(-t / mu0) / mu0 per unit depth; what goes up at cosine mu leaves with
  // exp(-t / mu), down with exp(-(tau - t) / mu). The depth integrals in closed form:
  //   up:   mu / (mu + mu0) (1 - exp(-tau (1 / mu0 + 1 / mu)))
  //   down: (exp(-tau / mu) - exp(-tau / mu0)) / (k mu0), k = 1 / mu0 - 1 / mu
  // and the directions by quadrature over mu and the azimuth (HG about the beam's direction).
  SingleScattering s;
  const double mu0 = p.mu0, tau = p.tau;
  const PhaseNodes phase = phase_nodes(mu0, p.g, 600);
  for (size_t i = 0; i < phase.nodes.size(); ++i) {
    auto [mu, dmu] = phase.nodes[i];
    double up_depth = mu / (mu + mu0) * -std::expm1(-tau * (1 / mu0 + 1 / mu));
    double k = 1 / mu0 - 1 / mu;
    double down_depth = std::abs(k * tau) < 1e-6
                            ? tau / mu0 * std::exp(-tau / mu)
                            : (std::exp(-tau / mu) - std::exp(-tau / mu0)) / (k * mu0);
    s.R += p.albedo * phase.up[i] * up_depth * dmu;
    s.T += p.albedo * phase.down[i] * down_depth * dmu;
  }
  return s;
}

void to_json(nlohmann::json& j, const LblSlabResult& r) {
  j = {{"solver", "lbl"},
       {"R", r.R},
       {"T", r.T},
       {"R_diffuse", r.R_diffuse},
       {"R_specular", r.R_specular},
       {"T_diffuse", r.T_diffuse},
       {"T_direct", r.T_direct},
       {"R_single", r.R_single},
       {"T_single", r.T_single},
       {"R_forward", r.R_forward},
       {"T_forward", r.T_forward},
       {"R_lattice", r.R_lattice},
       {"T_lattice", r.T_lattice},
       {"absorbed", r.absorbed},
       {"orders", nlohmann::json::array()},
       {"layers", r.layers},
       {"steps", r.steps},
       {"converged", r.converged}};
  for (const SingleScattering& o : r.orders) j["orders"].push_back({{"R", o.R}, {"T", o.T}});
}

LblSlabResult run_lbl_slab(gpu::ClContext& cl, const SlabParams& p, const LblSlabOptions& o) {
  check(std::isfinite(p.tau), "tau",
        "the lbl solver needs a finite slab (the lattice has a node per layer)");
  check(p.tau > 0 && p.tau <= 1000, "tau", "must be in (0, 1000] for the lbl solver");
  check(p.albedo >= 0 && p.albedo <= 1, "albedo", "must be in [0, 1]");
  check(p.g > -1 && p.g < 1, "g", "must be in (-1, 1)");
  check(p.mu0 > 0 && p.mu0 <= 1, "mu0", "must be in (0, 1]");
  check(p.ior == 1, "ior", "the lbl solver has no refracting boundary: only 1 is supported");
  check(o.orders == 0 || (o.orders >= 2 && o.orders <= 32), "orders", "must be 0 or in [2, 32]");
  check(o.orders == 0 || p.tau <= 100, "tau",
        "must be at most 100 with orders (each order's quadrature grows with the layers squared)");

  LblSlabResult r;
  check(o.gathers >= 1 && o.gathers <= kMaxGathers, "gathers",
        "must be in [1, " + std::to_string(kMaxGathers) + "]");
  r.layers = std::clamp(static_cast<int>(std::ceil(p.tau / o.layer_tau)), 32, 20000);
  const int factor = 1 << kOrderLevel;  // the coarse gathers' layers (second.hpp)
  r.layers = (r.layers + factor - 1) / factor * factor;
  const double dtau = p.tau / r.layers;  // sigma_t dx of a layer (lattice units: dx = 1)
  // The lattice: one node per layer, the same coefficients for all channels.
  Volume v;
  v.nx = v.ny = 1;
  v.nz = r.layers;
  v.voxel = 1;
  v.sigma_s.assign(3 * v.count(), static_cast<float>(p.albedo * dtau));
  v.sigma_t.assign(3 * v.count(), static_cast<float>(dtau));
  LatticeOptions lo{.blocked = false, .edges = {Edge::Periodic, Edge::Periodic, Edge::Open}};
  LatticeCoefficients coeffs = lattice_coefficients(v, p.g);
  // Escape: per layer, the transport's chance that isotropic emission there leaves without
  // another collision (the delta-Eddington scaled medium) against the lattice's own (1/6 up and
  // 1/6 down through the layers' (1 - pt); sideways packets never leave a periodic column).
  const PhaseNodes isotropic = phase_nodes(1, 0, 400);
  const auto& esc_nodes = isotropic.nodes;
  const double dtau_s = (1 - p.albedo * p.g) * dtau;
  std::vector<float> escape(3 * v.count(), 1.f);
  if (o.escape) {
    const double keep = 1 - coeffs.pt[0];
    std::vector<float> exact(escape.size()), lattice(escape.size());
    for (int k = 0; k < r.layers; ++k) {
      auto [up, down] = layer_escape_phase(k, r.layers, dtau_s, isotropic);
      for (int ch = 0; ch < 3; ++ch) {
        exact[3 * k + ch] = static_cast<float>(up + down);
        lattice[3 * k + ch] =
            static_cast<float>((std::pow(keep, k) + std::pow(keep, r.layers - 1 - k)) / 6);
      }
    }
    escape = escape_factor(exact, lattice);
    for (size_t i = 0; i < coeffs.ps.size(); ++i) coeffs.ps[i] *= escape[i];
  }
  Lattice lattice(cl, coeffs, lo);
  // The beam (power 1 per node's cross-section, travelling +z), delta-Eddington scaled like the
  // lattice: the forward fraction g of its scattering stays in the beam, so it attenuates with
  // sigma_t' = (1 - a g) sigma_t and scatters in layer k what enters it times
  // a' (1 - exp(-dtau' / mu0)), a' = a (1 - g) / (1 - a g).
  const double dtau_r = (1 - p.albedo * p.g) * dtau;
  const double albedo_r = dtau_r > 0 ? p.albedo * (1 - p.g) * dtau / dtau_r : 0;
  std::vector<float> source(3 * v.count());
  for (int k = 0; k < r.layers; ++k) {
    double in = std::exp(-k * dtau_r / p.mu0);
    double s = in * albedo_r * -std::expm1(-dtau_r / p.mu0);
    for (int c = 0; c < 3; ++c) source[3 * k + c] = static_cast<float>(s);
  }
  // With `second`: the lattice from the second scattering (in the scaled medium), which the
  // view then sees next to the lattice's irradiance. With `orders` N: the real medium's orders 2
  // to N exactly (slab_next_order), each order's light by HG(g |m|) about its mean direction,
  // and the lattice from what order N's light does not let out directly.
  std::vector<float> second;
  if (o.orders >= 2) {
    std::vector<double> emitted(r.layers), mean;
    for (int k = 0; k < r.layers; ++k)
      emitted[k] = std::exp(-k * dtau / p.mu0) * p.albedo * -std::expm1(-dtau / p.mu0);
    std::vector<PhaseNodes> phase(r.layers, phase_nodes(p.mu0, p.g, 200));
    std::vector<double> escapes(r.layers);  // E per layer of the last order's light
    for (int order = 2; order <= o.orders; ++order) {
      emitted = slab_next_order(emitted, phase, dtau, p.albedo, mean);
      SingleScattering leaves;
      for (int k = 0; k < r.layers; ++k) {
        phase[k] = axis_phase(p.g, mean[k], 200);
        auto [e_up, e_down] = layer_escape_phase(k, r.layers, dtau, phase[k]);
        leaves.R += emitted[k] * e_up;
        leaves.T += emitted[k] * e_down;
        escapes[k] = e_up + e_down;
      }
      r.orders.push_back(leaves);
    }
    // The lattice's source: order N's light that interacts again, 1 - E of it (E its escape
    // through the real medium by its phase), emitted isotropically in the scaled medium, whose
    // isotropic emission interacts again 1 - P' of the time (P' as the escape correction's).
    for (int k = 0; k < r.layers; ++k) {
      auto [s_up, s_down] = layer_escape_phase(k, r.layers, dtau_s, isotropic);
      double keep = (1 - escapes[k]) / std::max(1e-12, 1 - s_up - s_down);
      for (int c = 0; c < 3; ++c) source[3 * k + c] = static_cast<float>(emitted[k] * keep);
    }
  } else if (o.second) {
    // `second` holds what the view sees (orders 2 to gathers + 1), the lattice starts from the
    // last of them.
    second = slab_second(source, r.layers, dtau_r, albedo_r, esc_nodes);
    source = second;
    for (int k = 2; k <= o.gathers; ++k) {
      source = slab_next_coarse(source, r.layers, factor, dtau_r, albedo_r, esc_nodes);
      for (size_t i = 0; i < source.size(); ++i) second[i] += source[i];
    }
  }
  for (size_t i = 0; i < source.size(); ++i) source[i] *= escape[i];
  lattice.set_source(source);
  Convergence c = lattice.converge(o.tolerance, o.max_steps, 64);
  r.steps = c.steps;
  r.converged = c.converged;
  r.T_direct = std::exp(-p.tau / p.mu0);
  // What leaves the lattice per step: -z out of the first layer, +z out of the last; what the
  // scaled beam carries out beyond the unscattered part was scattered forward.
  std::vector<float> f = lattice.state();
  const size_t n = lattice.nodes();
  const int up = 4, down = 5;  // +z, -z
  r.R_lattice = f[(down * 3) * n + 0];
  r.T_lattice = f[(up * 3) * n + (n - 1)] + std::exp(-r.layers * dtau_r / p.mu0) - r.T_direct;
  // As the pipeline's view pass sees the medium with tms 0 and scaled_view 0 (tms 1, the
  // pipeline's default, corrects radiance away from the forward peak, which a flux integrates
  // too: docs/pipelines/lbl.md): the single
  // scattering exactly (HG phase, the real medium); the second scattering (with `second`) and
  // the lattice's scattered power per layer (the third and later events; without `second`, the
  // second and later) emitted isotropically through the real medium, leaving each face with the
  // transport's escape probability from a uniform layer (layer_escape); with g != 0 the forward-
  // scattered light (below). scaled_view 1 with g != 0: the whole slab as the delta-Eddington
  // scaled problem (tau (1 - a g), albedo a (1 - g) / (1 - a g), isotropic; not the pipeline's
  // scaled_view 1, which keeps the real single term), its forward peak left in the beam, which
  // then carries the light scattered forward out of the far face. With `orders`: the single
  // scattering and the exact orders in the real medium, the lattice's light as the scaled
  // problem emits and attenuates it.
  const bool scaled = o.scaled_view && p.g != 0 && o.orders < 2;
  SlabParams single_params = p;
  if (scaled) {
    single_params.tau = p.tau * (1 - p.albedo * p.g);
    single_params.albedo = albedo_r;
    single_params.g = 0;
  }
  SingleScattering single = slab_single_scattering(single_params);
  r.R_single = single.R;
  r.T_single = single.T;
  const double forward = std::exp(-single_params.tau / p.mu0) - r.T_direct;
  std::vector<float> irr = lattice.irradiance();
  // The lattice's light in the scaled medium: (1 - g) irr through layers of dtau (1 - a g).
  const bool lattice_scaled = scaled || o.orders >= 2;
  const double view_dtau = lattice_scaled ? dtau_s : dtau;
  const double view_emit = lattice_scaled ? 1 - p.g : 1;
  double R_multiple = 0, T_multiple = 0;
  for (const SingleScattering& order : r.orders) {
    R_multiple += order.R;
    T_multiple += order.T;
  }
  for (int k = 0; k < r.layers; ++k) {
    // irr in the real sigma_s's share; the second scattering in the scaled medium's.
    double e = (irr[3 * k] + (!second.empty() ? second[3 * k] / (1 - p.g) : 0.0)) * view_emit;
    if (!(e > 0)) continue;
    auto [e_up, e_down] = layer_escape_phase(k, r.layers, view_dtau, isotropic);
    R_multiple += e * e_up;
    T_multiple += e * e_down;
  }
  // The pipeline's view (not scaled, no orders), as the march's `extra` and the view's
  // multiple_emission: what the scaled beam carries beyond the real one was scattered forward;
  // its scattering in each layer (sigma_s times that light's path there) is emitted with the HG
  // phase about the beam and seen through the real medium.
  if (!scaled && o.orders < 2 && p.g != 0) {
    const PhaseNodes phase = phase_nodes(p.mu0, p.g, 400);
    for (int k = 0; k < r.layers; ++k) {
      double q = std::exp(-k * dtau_r / p.mu0), real = std::exp(-k * dtau / p.mu0);
      double path_q = q * -std::expm1(-dtau_r / p.mu0) / dtau_r;
      double path_real = real * -std::expm1(-dtau / p.mu0) / dtau;
      double e = p.albedo * dtau * (path_q - path_real);
      if (!(e > 0)) continue;
      auto [e_up, e_down] = layer_escape_phase(k, r.layers, dtau, phase);
      r.R_forward += e * e_up;
      r.T_forward += e * e_down;
    }
    R_multiple += r.R_forward;
    T_multiple += r.T_forward;
  }
  r.R_diffuse = r.R_single + R_multiple;
  r.T_diffuse = r.T_single + T_multiple + forward;
  r.R = r.R_diffuse + r.R_specular;
  r.T = r.T_diffuse + r.T_direct;
  r.absorbed = 1 - r.R - r.T;
  return r;
}

}  // namespace scatter::lbl
