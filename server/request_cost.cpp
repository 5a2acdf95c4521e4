// Api::check_cost: a request's estimated cost against --max-request-mb and --max-render-s.
#include <cmath>
#include <string>

#include "pipelines/cost.hpp"
#include "server/api.hpp"

namespace scatter::server {
namespace {

// 3 significant digits, but whole numbers from 1000 up ("1720", not "1.72e+03").
std::string amount(double v) {
  return v >= 1000 && v < 1e15 ? std::to_string(static_cast<long long>(std::llround(v)))
                               : short_number(v);
}

}  // namespace

void Api::check_cost(const ApiOptions& options, const std::string& pipeline, const Scene& scene,
                     const std::string& terms, const Settings& settings, bool bake,
                     std::optional<double> max_error) {
  RenderRequest request;
  request.settings = settings;
  request.max_error = max_error;
  if (!terms.empty()) request.terms = parse_terms(terms);
  CostEstimate c = estimate_cost(pipeline, scene, request, bake);
  const double mb = c.bytes() / double(1 << 20);
  if (options.max_request_mb > 0 && mb > options.max_request_mb)
    throw RequestTooCostly(c.memory_field, "would need about " + amount(mb) + " MB (" + c.summary +
                                               "), over this server's limit of " +
                                               short_number(options.max_request_mb) +
                                               " MB per request (--max-request-mb)");
  // A bake reports progress and can be cancelled; its time is not limited.
  if (!bake && options.max_render_s > 0 && c.seconds > options.max_render_s)
    throw RequestTooCostly(
        c.time_field, "would take about " + amount(c.seconds) + " s, over this server's limit of " +
                          short_number(options.max_render_s) + " s per render (--max-render-s)");
}

}  // namespace scatter::server
