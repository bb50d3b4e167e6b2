# cmake -DBUILD_DIR=... -DWORK_DIR=... -DDOWNSTREAM_SOURCE=... -DGENERATOR=... -DCXX_COMPILER=... -DBUILD_TYPE=... -P run_package_test.cmake
set(prefix ${WORK_DIR}/prefix)
set(downstream_build ${WORK_DIR}/downstream-build)
file(REMOVE_RECURSE ${prefix} ${downstream_build})

function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "package test: ${step} failed (${result})\n${out}\n${err}")
  endif()
  message(STATUS "package test: ${step}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f lib/cmake/chlorovdb/chlorovdbConfig.cmake lib/cmake/chlorovdb/chlorovdbTargets.cmake
          include/chlorovdb/scene/scene_loader.h include/chlorovdb/core/vec.h
          lib/libchlorovdb_core.a lib/libchlorovdb_integrator.a bin/chlorovdb share/chlorovdb/spectra/cie_d65.csv)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "package test: ${f} was not installed")
  endif()
endforeach()
file(GLOB_RECURSE leaked ${prefix}/include/chlorovdb/cli/*)
if(leaked)
  message(FATAL_ERROR "package test: CLI headers installed: ${leaked}")
endif()

# Only the prefix: the downstream project must not see this source or build tree.
run("configure downstream" ${CMAKE_COMMAND} -S ${DOWNSTREAM_SOURCE} -B ${downstream_build} -G ${GENERATOR}
    -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_PREFIX_PATH=${prefix})
file(READ ${downstream_build}/CMakeCache.txt cache)
if(cache MATCHES "chlorovdb_DIR:PATH=([^\n]*)")
  if(NOT CMAKE_MATCH_1 STREQUAL "${prefix}/lib/cmake/chlorovdb")
    message(FATAL_ERROR "package test: found chlorovdb at ${CMAKE_MATCH_1}, not in the prefix")
  endif()
endif()
run("build downstream" ${CMAKE_COMMAND} --build ${downstream_build})
run("run downstream" ${downstream_build}/downstream_app ${WORK_DIR})
if(NOT last_output MATCHES "downstream: ok")
  message(FATAL_ERROR "package test: unexpected output: ${last_output}")
endif()
run("installed CLI" ${prefix}/bin/chlorovdb --help)
