#pragma once
// Spectral tables in CSV (spectra/*.csv): `#` comment lines (the provenance),
// a header row `wavelength_nm,<col>,...`, then one row per wavelength in nm.
// Columns other than the wavelength may hold text (e.g. a per-row source code);
// only the columns a caller asks for must be numeric. Bad data throws
// InputError naming the file, the line, the column and the offending value.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "spectra/spectrum.h"

namespace chlorovdb {

struct CsvOptions {
  bool allow_negative = false;  // signed data (e.g. derivatives); spectra are non-negative
};

struct CsvColumn {
  std::string name;
  std::vector<std::string> text;  // cells verbatim (trimmed)
  std::vector<double> value;      // parsed cells; NaN where a cell is not a number
  bool numeric = true;            // every cell parsed as a number (finite or not)
};

struct CsvTable {
  std::filesystem::path path;
  std::string source;                // the `#` lines, '#' and one space removed, joined by '\n'
  int header_line = 0;               // 1-based line number of the header row
  std::vector<int> line;             // 1-based line number of each data row
  std::vector<double> wavelength_nm; // strictly increasing (checked at float precision)
  std::vector<CsvColumn> columns;    // the columns after wavelength_nm, in file order

  // Throws InputError (with the nearest column name) when there is no such column.
  const CsvColumn& column(std::string_view name) const;
  // The column as floats, checked: numeric, finite, non-negative unless allowed.
  std::vector<float> values(std::string_view name, CsvOptions options = {}) const;
};

// Reads and checks the structure: header, cell counts, wavelengths (numeric,
// finite, strictly increasing) and at least 2 data rows.
CsvTable read_csv_table(const std::filesystem::path& path);

// A tabulated Spectrum from one column (default: the first after wavelength_nm).
Spectrum load_spectrum_csv(const std::filesystem::path& path, std::string_view column = {}, CsvOptions options = {});

}  // namespace chlorovdb
