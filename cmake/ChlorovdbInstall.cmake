# Install rules and the exported CMake package (issue 8).
#
#   cmake --install build --prefix /opt/chlorovdb
#
# installs the static libraries (lib/), their headers (include/chlorovdb/<module>/*.h,
# so downstream code includes "scene/scene_loader.h" as the project does), the CLI
# (bin/chlorovdb), the spectral tables (share/chlorovdb/spectra) and a CMake package:
#
#   find_package(chlorovdb CONFIG REQUIRED)
#   target_link_libraries(app PRIVATE chlorovdb::chlorovdb)   # every module
#   target_link_libraries(app PRIVATE chlorovdb::scene)        # or one module and what it needs
#
# The module targets come from cmake/Modules.cmake, which roots include paths at
# src/ in the source tree; here they are rewritten to a build/install pair so the
# export does not point into the source tree. Tested by tests/package.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CHLOROVDB_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/chlorovdb" CACHE STRING
    "Where chlorovdbConfig.cmake is installed, relative to the prefix")
set(CHLOROVDB_INSTALL_SPECTRADIR "${CMAKE_INSTALL_DATADIR}/chlorovdb/spectra")

# Every module library: chlorovdb_<folder> for each src/<folder> that defines one.
file(GLOB _module_dirs LIST_DIRECTORIES true RELATIVE ${PROJECT_SOURCE_DIR}/src ${PROJECT_SOURCE_DIR}/src/*)
set(_chlorovdb_exported)
foreach(_m ${_module_dirs})
  set(_t chlorovdb_${_m})
  if(NOT TARGET ${_t})
    continue()
  endif()
  get_target_property(_dirs ${_t} INTERFACE_INCLUDE_DIRECTORIES)
  list(REMOVE_ITEM _dirs "${PROJECT_SOURCE_DIR}/src")
  list(APPEND _dirs "$<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>"
                    "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/chlorovdb>")
  set_target_properties(${_t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_dirs}" EXPORT_NAME ${_m})
  # Compile definitions such as CHLOROVDB_SPECTRA_DIR name source-tree paths; they
  # matter to the module's own sources only, so downstream builds do not get them.
  get_target_property(_defs ${_t} INTERFACE_COMPILE_DEFINITIONS)
  if(_defs)
    set(_wrapped)
    foreach(_d ${_defs})
      list(APPEND _wrapped "$<BUILD_INTERFACE:${_d}>")
    endforeach()
    set_target_properties(${_t} PROPERTIES INTERFACE_COMPILE_DEFINITIONS "${_wrapped}")
  endif()
  list(APPEND _chlorovdb_exported ${_t})
endforeach()

# chlorovdb::chlorovdb: every module.
add_library(chlorovdb_all INTERFACE)
target_link_libraries(chlorovdb_all INTERFACE ${_chlorovdb_exported})
set_target_properties(chlorovdb_all PROPERTIES EXPORT_NAME chlorovdb)
add_library(chlorovdb::chlorovdb ALIAS chlorovdb_all)

install(TARGETS ${_chlorovdb_exported} chlorovdb_all
        EXPORT chlorovdbTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/chlorovdb)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/chlorovdb
        FILES_MATCHING PATTERN "*.h"
        PATTERN "cli" EXCLUDE)
if(TARGET chlorovdb)
  install(TARGETS chlorovdb RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/spectra/ DESTINATION ${CHLOROVDB_INSTALL_SPECTRADIR})

install(EXPORT chlorovdbTargets NAMESPACE chlorovdb:: DESTINATION ${CHLOROVDB_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/chlorovdbConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/chlorovdbConfig.cmake
                              INSTALL_DESTINATION ${CHLOROVDB_INSTALL_CMAKEDIR}
                              PATH_VARS CHLOROVDB_INSTALL_SPECTRADIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/chlorovdbConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/chlorovdbConfig.cmake ${PROJECT_BINARY_DIR}/chlorovdbConfigVersion.cmake
        DESTINATION ${CHLOROVDB_INSTALL_CMAKEDIR})
