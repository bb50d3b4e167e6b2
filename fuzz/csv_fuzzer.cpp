// libFuzzer target: spectrum CSV reader (spectra/csv.h). Bytes -> a temporary
// .csv file -> read_csv_table, every column's values() (strict and signed), and
// load_spectrum_csv for the default column, whose Spectrum is then evaluated.
// A valid table must give finite values; everything else must be an InputError.
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.h"
#include "spectra/csv.h"

using namespace chlorovdb;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::use_one_thread();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("input.csv", data, size);
  fuzz::run_expecting_input_errors("read_csv_table", [&] {
    const CsvTable table = read_csv_table(path);
    for (const CsvColumn& c : table.columns) {
      for (const bool signed_ok : {false, true}) {
        try {
          CsvOptions options;
          options.allow_negative = signed_ok;
          const std::vector<float> v = table.values(c.name, options);
          if (v.size() != table.wavelength_nm.size()) std::abort();  // a checked column has one value per row
          for (float x : v)
            if (!std::isfinite(x) || (!signed_ok && x < 0.f)) std::abort();
        } catch (const InputError&) {
        }
      }
    }
  });
  fuzz::run_expecting_input_errors("load_spectrum_csv", [&] {
    const Spectrum s = load_spectrum_csv(path);
    for (float lambda : {0.f, 250.f, 360.f, 555.5f, 830.f, 1e6f}) {
      const float v = s(lambda);
      if (!std::isfinite(v) || v < 0.f) {
        std::fprintf(stderr, "load_spectrum_csv: value %g at %g nm\n", double(v), double(lambda));
        std::abort();
      }
    }
    // The integral must be finite too: values near FLT_MAX once passed the reader and
    // overflowed it (docs/robustness.md, finding F3).
    const float total = s.integral(250.f, 830.f);
    if (!std::isfinite(total)) {
      std::fprintf(stderr, "load_spectrum_csv: integral %g\n", double(total));
      std::abort();
    }
  });
  return 0;
}
