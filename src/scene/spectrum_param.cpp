#include "scene/spectrum_param.h"

#include <fmt/format.h>

#include "core/error.h"
#include "spectra/csv.h"
#include "spectra/library.h"

namespace chlorovdb {

namespace {

// Errors from the table readers name their own file; add where the scene asked for the table.
template <typename F>
Spectrum with_scene_context(const ParamReader& params, const std::string& key, F&& load) {
  try {
    return load();
  } catch (const InputError& e) {
    throw InputError(fmt::format("{} (from {}: {})", e.what(), params.file().string(), params.key_path(key)));
  }
}

}  // namespace

Spectrum read_spectrum(ParamReader& params, const std::string& key) {
  const nlohmann::json& v = params.raw(key);
  {
    if (v.is_number()) {
      const float c = params.require_float(key, 0.f);
      return Spectrum::constant(c);
    }
    if (v.is_string()) {
      const std::string s = v.get<std::string>();
      if (s.size() > 4 && s.substr(s.size() - 4) == ".csv") {
        const auto path = params.require_path(key);
        return with_scene_context(params, key, [&] { return load_spectrum_csv(path); });
      }
      return with_scene_context(params, key, [&] { return named_spectrum(s); });
    }
    if (v.is_object()) {
      ParamReader obj = params.child(key);
      Spectrum result;
      if (obj.has("csv")) {
        const auto path = obj.require_path("csv");
        const std::string column = obj.get_string("column", "");
        result = with_scene_context(obj, "csv", [&] { return load_spectrum_csv(path, column); });
      } else if (obj.has("blackbody")) {
        result = Spectrum::blackbody(obj.require_float("blackbody", 1.f, 1e6f));
      } else if (obj.has("gaussian")) {
        const auto g = obj.get_floats("gaussian", {}, 2);
        if (g.size() != 2 || !(g[1] > 0.f)) obj.fail("gaussian", "expected [mean_nm, sigma_nm] with sigma > 0");
        result = Spectrum::gaussian(g[0], g[1]);
      } else if (obj.has("table")) {
        ParamReader table = obj.child("table");
        auto lambda = table.get_floats("lambda", {}, 2);
        auto value = table.get_floats("value", {}, 2);
        table.finish();
        try {
          result = Spectrum::tabulated(std::move(lambda), std::move(value), params.key_path(key));
        } catch (const std::invalid_argument& e) {
          obj.fail("table", e.what());
        }
      } else {
        params.fail(key, "a spectrum object needs one of \"csv\", \"blackbody\", \"gaussian\", \"table\"");
      }
      obj.finish();
      return result;
    }
  }
  params.fail(key, "expected a spectrum: a number, a table name, a .csv path or an object");
}

Spectrum read_spectrum(ParamReader& params, const std::string& key, const Spectrum& fallback) {
  return params.has(key) ? read_spectrum(params, key) : fallback;
}

}  // namespace chlorovdb
