#include "spectra/csv.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <fstream>
#include <limits>
#include <optional>

#include "core/error.h"

namespace chlorovdb {

namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> split_cells(std::string_view row) {
  std::vector<std::string> cells;
  size_t start = 0;
  while (true) {
    const size_t comma = row.find(',', start);
    cells.emplace_back(trim(row.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

// A whole cell as a number; "nan" and "inf" parse (and are rejected later with their line).
std::optional<double> parse_number(std::string_view cell) {
  if (cell.size() > 1 && cell[0] == '+') cell.remove_prefix(1);  // from_chars rejects a leading '+'
  double v = 0.0;
  const auto [end, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  if (ec != std::errc() || end != cell.data() + cell.size() || cell.empty()) return std::nullopt;
  return v;
}

std::string where(int line, std::string_view column) { return fmt::format("line {}, column {}", line, column); }

}  // namespace

CsvTable read_csv_table(const std::filesystem::path& path) {
  const std::string file = path.string();
  // A device, FIFO or directory would be read forever (/dev/zero: one endless
  // line) or give a confusing parse error: only regular files are tables.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw InputError(file, "", "", "not a regular file (a spectral table must be a CSV file, not a directory, device or pipe)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, "", "", "cannot open spectral table (missing or unreadable file)");

  CsvTable table;
  table.path = path;
  std::vector<std::string> header;
  std::string text;
  int line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    const std::string_view line = trim(text);
    if (line.empty()) continue;
    if (line[0] == '#') {
      std::string_view comment = line.substr(1);
      if (!comment.empty() && comment[0] == ' ') comment.remove_prefix(1);
      if (!table.source.empty()) table.source += '\n';
      table.source += comment;
      continue;
    }
    if (header.empty()) {
      header = split_cells(line);
      table.header_line = line_number;
      if (header[0] != "wavelength_nm")
        throw InputError(file, fmt::format("line {}", line_number), header[0],
                         "the header row must start with the column 'wavelength_nm'");
      for (size_t c = 1; c < header.size(); ++c) {
        for (size_t d = 0; d < c; ++d)
          if (header[d] == header[c])
            throw InputError(file, fmt::format("line {}", line_number), header[c], "duplicate column name");
        table.columns.push_back({header[c], {}, {}, true});
      }
      continue;
    }

    const std::vector<std::string> cells = split_cells(line);
    if (cells.size() != header.size())
      throw InputError(file, fmt::format("line {}", line_number), std::string(line),
                       fmt::format("expected {} comma-separated values (as in the header), found {}", header.size(), cells.size()));
    const std::optional<double> lambda = parse_number(cells[0]);
    if (!lambda) throw InputError(file, where(line_number, header[0]), cells[0], "not a number");
    if (!std::isfinite(float(*lambda))) throw InputError(file, where(line_number, header[0]), cells[0], "not a finite number");
    // Checked at float precision: that is what Spectrum stores.
    if (!table.wavelength_nm.empty()) {
      const float previous = float(table.wavelength_nm.back());
      if (float(*lambda) == previous)
        throw InputError(file, where(line_number, header[0]), cells[0],
                         fmt::format("duplicate wavelength (also on line {})", table.line.back()));
      if (float(*lambda) < previous)
        throw InputError(file, where(line_number, header[0]), cells[0],
                         fmt::format("wavelengths must increase; line {} has {}", table.line.back(), previous));
    }
    table.wavelength_nm.push_back(*lambda);
    table.line.push_back(line_number);
    for (size_t c = 1; c < cells.size(); ++c) {
      CsvColumn& column = table.columns[c - 1];
      const std::optional<double> v = parse_number(cells[c]);
      column.numeric = column.numeric && v.has_value();
      column.value.push_back(v.value_or(std::numeric_limits<double>::quiet_NaN()));
      column.text.push_back(cells[c]);
    }
  }
  if (in.bad()) throw InputError(file, "", "", "read error");
  if (header.empty()) throw InputError(file, "", "", "no header row 'wavelength_nm,...' found");
  if (table.line.size() < 2)
    throw InputError(file, fmt::format("line {}", table.line.empty() ? table.header_line : table.line.back()),
                     fmt::format("{} data row{}", table.line.size(), table.line.size() == 1 ? "" : "s"),
                     "a spectral table needs at least 2 data rows");
  return table;
}

const CsvColumn& CsvTable::column(std::string_view name) const {
  std::vector<std::string> names;
  for (const CsvColumn& c : columns) {
    if (c.name == name) return c;
    names.push_back(c.name);
  }
  const std::string nearest = nearest_word(name, names);
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  throw InputError(path.string(), fmt::format("line {} (header)", header_line), name,
                   fmt::format("no such column{}; columns: {}", nearest.empty() ? "" : fmt::format(" (did you mean '{}'?)", nearest),
                               known.empty() ? "(none)" : known));
}

std::vector<float> CsvTable::values(std::string_view name, CsvOptions options) const {
  const CsvColumn& c = column(name);
  std::vector<float> out(c.value.size());
  for (size_t r = 0; r < c.value.size(); ++r) {
    const double v = c.value[r];
    if (!c.numeric && !parse_number(c.text[r]))
      throw InputError(path.string(), where(line[r], c.name), c.text[r], "not a number");
    // Checked after conversion: a value beyond float range would become infinite.
    if (!std::isfinite(float(v))) throw InputError(path.string(), where(line[r], c.name), c.text[r], "not a finite number");
    if (v < 0.0 && !options.allow_negative)
      throw InputError(path.string(), where(line[r], c.name), c.text[r],
                       "negative value (only signed columns may be negative: CsvOptions{.allow_negative = true})");
    out[r] = float(v);
  }
  return out;
}

Spectrum load_spectrum_csv(const std::filesystem::path& path, std::string_view column, CsvOptions options) {
  const CsvTable table = read_csv_table(path);
  if (column.empty() && table.columns.empty())
    throw InputError(path.string(), fmt::format("line {} (header)", table.header_line), "wavelength_nm",
                     "the table has no data column after wavelength_nm");
  const std::string name = column.empty() ? table.columns.front().name : std::string(column);
  std::vector<float> values = table.values(name, options);
  std::vector<float> lambda(table.wavelength_nm.begin(), table.wavelength_nm.end());
  const std::string title = table.source.substr(0, table.source.find('\n'));
  std::string source = fmt::format("{} [{}]", path.filename().string(), name);
  if (!title.empty()) source += ": " + title;
  try {
    return Spectrum::tabulated(std::move(lambda), std::move(values), std::move(source));
  } catch (const std::invalid_argument& e) {
    throw InputError(path.string(), "column " + name, "", e.what());
  }
}

}  // namespace chlorovdb
