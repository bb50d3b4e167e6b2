#pragma once
// The scene options that render, reference, converge and measure share
// (--seed, --resolution, --wavelengths, --fluorescence, --transmittance, --aovs, --set):
// one place defines them and turns them into SceneOverrides.
#include <CLI/CLI.hpp>

#include "analysis/scene_variant.h"
#include "cli/options.h"
#include "scene/scene_loader.h"

namespace chlorovdb::cli {

template <class Args>
void add_scene_options(CLI::App* sub, Args& r) {
  sub->add_option("--seed", r.seed, "Seed of the per-pixel random streams")->check(Unsigned64);
  sub->add_option("--resolution", r.resolution, "Image size WxH, e.g. 640x480");
  sub->add_option("--wavelengths", r.wavelengths, "Wavelengths per camera path")->check(Integer(1, kMaxWavelengths));
  sub->add_option("--fluorescence", r.fluorescence, "auto | direct | full | reference | off");
  sub->add_option("--transmittance", r.transmittance, "auto | ratio | residual_ratio | delta");
  sub->add_option("--aovs", r.aovs,
                  "Compositing layers, comma-separated: alpha,depth,normal,albedo (replaces render.aovs; \"\" for none)");
  sub->add_option("--set", r.sets,
                  "KEY=VALUE: change any scene key in memory, e.g. media.solution.pigments[0].concentration=5 (repeatable)");
}

template <class Args>
SceneOverrides scene_overrides(const Args& a) {
  SceneOverrides o;
  o.seed = a.seed;
  o.wavelengths = a.wavelengths;
  o.fluorescence = a.fluorescence;
  o.transmittance = a.transmittance;
  o.aovs = a.aovs;
  if (a.resolution) parse_resolution(*a.resolution, o);
  return o;
}

}  // namespace chlorovdb::cli
