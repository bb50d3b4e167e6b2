#pragma once
// Spectrum-valued scene keys: a number, a table name, a CSV path, or an object
// ({"csv"}, {"blackbody"}, {"gaussian"}, {"table"}); docs/scene-format.md.
#include <string>

#include "scene/param_reader.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

Spectrum read_spectrum(ParamReader& params, const std::string& key);
Spectrum read_spectrum(ParamReader& params, const std::string& key, const Spectrum& fallback);

}  // namespace chlorovdb
