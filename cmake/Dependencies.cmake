# Every dependency comes from Debian 12's packages (see tools/install-deps.sh).
# Order matters: TBB, Imath and OpenEXR are found through their own CONFIG files
# *before* OpenVDB's module folder is put on CMAKE_MODULE_PATH, because that folder
# also ships outdated FindTBB/FindOpenEXR modules that would shadow them.
find_package(Threads REQUIRED)
find_package(TBB CONFIG REQUIRED)
find_package(Imath CONFIG REQUIRED)
find_package(OpenEXR CONFIG REQUIRED)
find_package(fmt CONFIG REQUIRED)
find_package(nlohmann_json CONFIG REQUIRED)
find_package(CLI11 CONFIG QUIET)
if(NOT CLI11_FOUND)
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp REQUIRED)
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  target_include_directories(CLI11::CLI11 INTERFACE ${CLI11_INCLUDE_DIR})
endif()
find_package(embree 3 CONFIG REQUIRED)
find_package(assimp CONFIG REQUIRED)

# OpenImageIO through pkg-config: its CMake config needs openimageio-tools and
# an /usr/include/opencv4 folder that Debian does not create.
find_package(PkgConfig REQUIRED)
pkg_check_modules(OIIO REQUIRED IMPORTED_TARGET OpenImageIO)

# OpenVDB (FindOpenVDB needs Boost iostreams because Debian builds it with delayed loading).
find_package(Boost REQUIRED COMPONENTS iostreams)
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED COMPONENTS openvdb nanovdb)

if(CHLOROVDB_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
if(CHLOROVDB_BUILD_BENCHMARKS)
  find_package(benchmark CONFIG REQUIRED)
endif()
