// Api::check_cost: a request's estimated cost against --max-request-mb and --max-render-s.
#include "pipelines/cost.hpp"
#include "pipelines/cost_support.hpp"
#include "server/api.hpp"

namespace scatter::server {

void Api::check_cost(const ApiOptions& options, const std::string& pipeline, const Scene& scene,
                     const std::string& terms, const Settings& settings, bool bake,
                     std::optional<double> max_error) {
  RenderRequest request;
  request.settings = settings;
  request.max_error = max_error;
  if (!terms.empty()) request.terms = parse_terms(terms);
  CostEstimate c = estimate_cost(pipeline, scene, request, bake);
  // Amounts in the summary's units (bytes_text: MB and GB of 10^6 and 10^9 bytes); the flag
  // counts MiB.
  const double limit = options.max_request_mb * double(1 << 20);
  if (options.max_request_mb > 0 && c.bytes() > limit)
    throw RequestTooCostly(c.memory_field,
                           "would need about " + cost::bytes_text(c.bytes()) + " (" + c.summary +
                               "), over this server's limit of " + cost::bytes_text(limit) +
                               " per request (--max-request-mb " +
                               exact_number(options.max_request_mb) + ")");
  // A bake reports progress and can be cancelled; its time is not limited.
  if (!bake && options.max_render_s > 0 && c.seconds > options.max_render_s)
    throw RequestTooCostly(c.time_field, "would take about " + cost::seconds_text(c.seconds) +
                                             ", over this server's limit of " +
                                             cost::seconds_text(options.max_render_s) +
                                             " per render (--max-render-s " +
                                             exact_number(options.max_render_s) + ")");
}

}  // namespace scatter::server
