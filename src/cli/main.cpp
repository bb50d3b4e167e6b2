#include <CLI/CLI.hpp>
#include <fmt/format.h>

int main(int argc, char** argv) {
  CLI::App app{"chlorovdb: spectral rendering of fluorescent pigments in OpenVDB volumes"};
  app.set_version_flag("--version", std::string("chlorovdb ") + CHLOROVDB_VERSION);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
