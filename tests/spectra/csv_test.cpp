#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "spectra/csv.h"
#include "spectra/library.h"

using namespace chlorovdb;

namespace {

// A CSV written to a fresh temporary file, removed afterwards.
class TempCsv {
 public:
  TempCsv(const std::string& name, const std::string& text)
      : path_(std::filesystem::temp_directory_path() / ("chlorovdb_csv_test_" + std::to_string(::getpid()) + "_" + name)) {
    std::ofstream(path_) << text;
  }
  ~TempCsv() { std::filesystem::remove(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// The error message for loading `text`, which must name the file, the line and the value.
std::string load_error(const std::string& name, const std::string& text, std::string_view column = {}) {
  TempCsv csv(name, text);
  try {
    load_spectrum_csv(csv.path(), column);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(csv.path().filename().string()), std::string::npos) << e.what();
    return e.what();
  }
  ADD_FAILURE() << name << ": no InputError";
  return {};
}

const char* kHeader = "# test table\nwavelength_nm,value\n";

}  // namespace

TEST(Csv, ReadsCommentsHeaderAndRows) {
  TempCsv csv("ok.csv", "# first line\n#second\nwavelength_nm,a,b,code\n400,1,2,X\n\n410,+3,4e-1,Y\n");
  const CsvTable t = read_csv_table(csv.path());
  EXPECT_EQ(t.source, "first line\nsecond");
  EXPECT_EQ(t.header_line, 3);
  EXPECT_EQ(t.line, (std::vector<int>{4, 6}));
  EXPECT_EQ(t.values("a"), (std::vector<float>{1, 3}));
  EXPECT_EQ(t.values("b"), (std::vector<float>{2, 0.4f}));
  EXPECT_FALSE(t.column("code").numeric);
  // The default column is the first after wavelength_nm.
  EXPECT_EQ(load_spectrum_csv(csv.path())(410.f), 3.f);
  EXPECT_EQ(load_spectrum_csv(csv.path(), "b")(400.f), 2.f);
}

TEST(Csv, ValuesWhoseIntegralWouldOverflowAreRefused) {
  const std::string msg = load_error("huge", std::string(kHeader) + "400,1\n500,3e38\n");
  EXPECT_NE(msg.find("3e+38"), std::string::npos) << msg;
  EXPECT_NE(msg.find("overflow"), std::string::npos) << msg;
}

TEST(Csv, UnsortedWavelengths) {
  const std::string m = load_error("unsorted.csv", std::string(kHeader) + "400,1\n420,1\n410,1\n");
  EXPECT_NE(m.find("line 5"), std::string::npos) << m;
  EXPECT_NE(m.find("410"), std::string::npos) << m;
}

TEST(Csv, DuplicateWavelengths) {
  const std::string m = load_error("duplicate.csv", std::string(kHeader) + "400,1\n410,1\n410,2\n");
  EXPECT_NE(m.find("line 5"), std::string::npos) << m;
  EXPECT_NE(m.find("= 410"), std::string::npos) << m;
  EXPECT_NE(m.find("duplicate"), std::string::npos) << m;
}

TEST(Csv, NotANumberAndInfinity) {
  std::string m = load_error("nan.csv", std::string(kHeader) + "400,1\n410,nan\n420,1\n");
  EXPECT_NE(m.find("line 4, column value = nan"), std::string::npos) << m;
  m = load_error("inf.csv", std::string(kHeader) + "400,1\n410,1\n420,inf\n");
  EXPECT_NE(m.find("line 5, column value = inf"), std::string::npos) << m;
  m = load_error("overflow.csv", std::string(kHeader) + "400,1\n410,1e50\n");
  EXPECT_NE(m.find("line 4, column value = 1e50"), std::string::npos) << m;
  m = load_error("text.csv", std::string(kHeader) + "400,1\n410,abc\n");
  EXPECT_NE(m.find("line 4, column value = abc: not a number"), std::string::npos) << m;
}

TEST(Csv, NegativeValuesUnlessAllowed) {
  const std::string text = std::string(kHeader) + "400,1\n410,-0.5\n";
  const std::string m = load_error("negative.csv", text);
  EXPECT_NE(m.find("line 4, column value = -0.5"), std::string::npos) << m;
  TempCsv csv("signed.csv", text);
  EXPECT_EQ(load_spectrum_csv(csv.path(), {}, CsvOptions{.allow_negative = true})(410.f), -0.5f);
}

TEST(Csv, TooFewRows) {
  const std::string m = load_error("short.csv", std::string(kHeader) + "400,1\n");
  EXPECT_NE(m.find("line 3 = 1 data row"), std::string::npos) << m;
  const std::string none = load_error("empty.csv", kHeader);
  EXPECT_NE(none.find("line 2 = 0 data rows"), std::string::npos) << none;
}

TEST(Csv, MissingColumnSuggestsNearest) {
  const std::string m =
      load_error("columns.csv", "wavelength_nm,a_per_m,a_unc_per_m\n400,1,0.1\n410,2,0.1\n", "a_per_mm");
  EXPECT_NE(m.find("line 1 (header) = a_per_mm"), std::string::npos) << m;
  EXPECT_NE(m.find("did you mean 'a_per_m'"), std::string::npos) << m;
}

TEST(Csv, WrongCellCountAndBadHeader) {
  std::string m = load_error("cells.csv", std::string(kHeader) + "400,1\n410,1,7\n");
  EXPECT_NE(m.find("line 4 = 410,1,7"), std::string::npos) << m;
  m = load_error("header.csv", "lambda,value\n400,1\n410,1\n");
  EXPECT_NE(m.find("line 1 = lambda"), std::string::npos) << m;
}

TEST(Csv, UnreadableFileIsNamed) {
  try {
    load_spectrum_csv("/nonexistent/dir/missing.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/missing.csv"), std::string::npos) << e.what();
  }
}

// Issue 7, finding F1: /dev/zero (or a FIFO, or /dev/stdin) used to be read forever.
TEST(Csv, DevicesAndDirectoriesAreNotTables) {
  for (const char* path : {"/dev/zero", "/dev/null"}) {
    if (!std::filesystem::exists(path)) continue;
    try {
      read_csv_table(path);
      ADD_FAILURE() << path << ": no InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_csv_table(std::filesystem::temp_directory_path()), InputError);
}

TEST(Csv, EveryShippedTableLoads) {
  // Non-numeric trailing columns (IOCCG source_code) do not matter unless requested.
  for (const std::string& name : spectrum_names()) EXPECT_NO_THROW(named_spectrum(name)) << name;
  const CsvTable ioccg = read_csv_table(spectra_dir() / "water_absorption_ioccg2018.csv");
  EXPECT_FALSE(ioccg.column("source_code").numeric);
  EXPECT_THROW(ioccg.values("source_code"), InputError);
}

TEST(Library, NamedSpectraAndUnknownName) {
  EXPECT_FLOAT_EQ(named_spectrum("D65")(560.f), 100.f);
  EXPECT_FLOAT_EQ(named_spectrum("chlorophyll_a")(427.75f), 111700.f);
  EXPECT_FLOAT_EQ(named_spectrum("water")(500.f), 0.0204f);
  try {
    named_spectrum("chlorophyl_a");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'chlorophyll_a'"), std::string::npos) << e.what();
  }
}
