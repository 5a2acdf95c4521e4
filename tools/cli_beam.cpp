// scatterd beam --b B --a A --g G [--length L --bins N --cone RAD --photons K --seed S] [--json]
// The beam-spread check of the psf pipeline's width formula (pipelines/psf/beam.hpp).
#include <iostream>

#include "pipelines/psf/beam.hpp"
#include "tools/commands.hpp"

namespace scatter::tools {

Handler add_beam_command(CLI::App& app) {
  auto o = std::make_shared<psf::BeamParams>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("beam",
                                     "Width of a collimated beam in a scattering medium: Monte "
                                     "Carlo against the psf pipeline's formula");
  cmd->add_option("--b", o->b, "Scattering coefficient")->capture_default_str();
  cmd->add_option("--a", o->a, "Absorption coefficient")->capture_default_str();
  cmd->add_option("--g", o->g, "Henyey-Greenstein asymmetry")->capture_default_str();
  cmd->add_option("--length", o->length, "Distance along the beam followed")->capture_default_str();
  cmd->add_option("--bins", o->bins, "Distance bins")->capture_default_str();
  cmd->add_option("--cone", o->cone,
                  "Tally events travelling within this angle (radians) of the axis")
      ->capture_default_str();
  cmd->add_option("--photons", o->photons, "Photons to trace")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str();
  cmd->add_flag("--json", *json, "Print one JSON object per line");
  return [o, json] {
    auto rows = psf::beam_spread(*o);
    if (!*json) std::cout << "distance,events,fwhm_mc,fwhm_model,fwhm_model_noshift\n";
    for (const auto& r : rows) {
      if (*json)
        std::cout << nlohmann::json(r).dump() << "\n";
      else
        std::cout << r.distance << "," << r.events << "," << r.fwhm_mc << "," << r.fwhm_model << ","
                  << r.fwhm_model_noshift << "\n";
    }
    return 0;
  };
}

}  // namespace scatter::tools
