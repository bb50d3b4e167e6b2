# chlorovdb_module(NAME DEPS <targets...> [DEFINES ...] [PCH <headers...>])
#   Builds src/NAME/*.cpp into the static library chlorovdb_NAME. A folder with
#   only headers becomes an INTERFACE library. Include paths are rooted at src/,
#   so code writes #include "spectra/spectrum.h". DEFINES are public compile definitions.
#   PCH names third-party headers that most of the module's files include and
#   that take seconds to parse (nlohmann/json, CLI11): they are parsed once per
#   module instead of once per file (CI builds from cold twice).
function(chlorovdb_module name)
  cmake_parse_arguments(ARG "" "" "DEPS;DEFINES;PCH" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  set(target chlorovdb_${name})
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC ${ARG_DEPS})
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter)
    target_compile_definitions(${target} PUBLIC ${ARG_DEFINES})
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    if(ARG_PCH)
      target_precompile_headers(${target} PRIVATE ${ARG_PCH})
    endif()
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
    target_compile_definitions(${target} INTERFACE ${ARG_DEFINES})
  endif()
endfunction()

# chlorovdb_test(NAME LIBS <targets...> [LABELS ...])
#   Called from tests/NAME/CMakeLists.txt. Builds tests/NAME/*.cpp into one GoogleTest binary test_NAME and registers
#   each test case with CTest. Statistical tests take their seeds from the code.
function(chlorovdb_test name)
  cmake_parse_arguments(ARG "" "" "LIBS;LABELS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  if(NOT sources)
    return()  # a folder whose tests are still being written
  endif()
  add_executable(test_${name} ${sources})
  target_link_libraries(test_${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_include_directories(test_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)  # scratch_dir.h, test_seed.h
  target_precompile_headers(test_${name} REUSE_FROM chlorovdb_test_pch)
  target_compile_definitions(test_${name} PRIVATE
    CHLOROVDB_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  gtest_discover_tests(test_${name} DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${name};${ARG_LABELS}"
    ENVIRONMENT "CHLOROVDB_SPECTRA=${PROJECT_SOURCE_DIR}/spectra")
endfunction()
