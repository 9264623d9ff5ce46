# ctest install.downstream: `cmake --install` the build into a scratch prefix,
# check the installed layout, then configure, build and run
# tests/install/downstream against it with the same compilers.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DDOWNSTREAM_DIR=... -DC_COMPILER=...
#         -DCXX_COMPILER=... [-DLAUNCHER=...] -DVERSION=... [-DMAN_PAGES=1] -P run_downstream.cmake
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

foreach(f bin/tsm bin/tsm-link bin/haptic-server bin/tsm-devices bin/virtual-slave bin/external-master-adapter
          include/tsmh/estimator/tsm_model.hpp include/tsmh/tsmh/master_state_t.hpp
          include/tsmh/tsmh/version.hpp share/tsm-haptics/profiles/tsm-console-2dof.yaml
          lib/udev/rules.d/70-tsm-haptics.rules share/doc/tsm-haptics/README.md
          share/doc/tsm-haptics/docs/install.md)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
if(MAN_PAGES)
  foreach(program tsm haptic-server tsm-devices virtual-slave external-master-adapter
          slave-node-skeleton tsm-link)
    if(NOT EXISTS ${prefix}/share/man/man1/${program}.1)
      message(FATAL_ERROR "man page not installed: ${program}.1")
    endif()
  endforeach()
endif()
file(GLOB_RECURSE config ${prefix}/*/tsmhConfig.cmake)
file(GLOB_RECURSE config_version ${prefix}/*/tsmhConfigVersion.cmake)
if(NOT config OR NOT config_version)
  message(FATAL_ERROR "tsmhConfig.cmake / tsmhConfigVersion.cmake not installed")
endif()

# The installed binaries run and find the installed profiles (not the source tree's).
run(${prefix}/bin/tsm-devices --version)
if(NOT out MATCHES "^tsm-devices \\(tsm-haptics\\) ${VERSION}")
  message(FATAL_ERROR "installed tsm-devices --version: ${out}")
endif()
run(${CMAKE_COMMAND} -E env --unset=TSMH_PROFILES_DIR ${prefix}/bin/tsm-devices --help)
string(FIND "${out}" "${prefix}/share/tsm-haptics/profiles" at)
if(at EQUAL -1)
  message(FATAL_ERROR "installed tsm-devices does not default to the installed profiles:\n${out}")
endif()

build_downstream(${WORK_DIR}/build ${prefix})
message(STATUS "downstream: ${out}")
run(${WORK_DIR}/build/downstream_all)
