# ctest install.package: the Debian packages CPack makes from this build
# (scripts/package does the same from a /usr-configured build), extracted with
# dpkg-deb -x into a scratch folder; the extracted programs' --version, and
# their profile lookup relative to the extracted tree; the downstream project
# (tests/install/downstream) built against the extracted -dev package.
#   cmake -DCPACK=... -DBUILD_DIR=... -DWORK_DIR=... -DVERSION=... -DARCH=...
#         -DDOWNSTREAM_DIR=... -DC_COMPILER=... -DCXX_COMPILER=... [-DLAUNCHER=...]
#         [-DMAN_PAGES=1] [-DLCM_JAVA=1] -P run_package.cmake
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
run(${CPACK} --config ${BUILD_DIR}/CPackConfig.cmake -G DEB -B ${WORK_DIR})
set(runtime ${WORK_DIR}/tsm-haptics_${VERSION}-1_${ARCH}.deb)
set(dev ${WORK_DIR}/tsm-haptics-dev_${VERSION}-1_${ARCH}.deb)
foreach(deb ${runtime} ${dev})
  if(NOT EXISTS ${deb})
    file(GLOB made ${WORK_DIR}/*.deb)
    message(FATAL_ERROR "not made: ${deb} (made: ${made})")
  endif()
endforeach()

# Declared dependencies: found by dpkg-shlibdeps for the programs, listed for -dev.
run(dpkg-deb -f ${runtime} Depends)
foreach(dep liblcm1 libyaml-cpp libhidapi-hidraw0 libusb-1.0-0 libnlopt)
  if(NOT out MATCHES "${dep}")
    message(FATAL_ERROR "tsm-haptics does not depend on ${dep}: ${out}")
  endif()
endforeach()
run(dpkg-deb -f ${dev} Depends)
foreach(dep "tsm-haptics \\(= ${VERSION}-1\\)" liblcm-dev libyaml-cpp-dev nlohmann-json3-dev)
  if(NOT out MATCHES "${dep}")
    message(FATAL_ERROR "tsm-haptics-dev does not depend on ${dep}: ${out}")
  endif()
endforeach()

set(root ${WORK_DIR}/root)
run(dpkg-deb -x ${runtime} ${root})
run(dpkg-deb -x ${dev} ${root})
foreach(f usr/lib/udev/rules.d/70-tsm-haptics.rules usr/share/tsm-haptics/profiles/tsm-console-2dof.yaml
          usr/share/doc/tsm-haptics/README.md usr/include/tsmh/estimator/tsm_model.hpp)
  if(NOT EXISTS ${root}/${f})
    message(FATAL_ERROR "not in the packages: ${f}")
  endif()
endforeach()
if(MAN_PAGES)
  foreach(program tsm haptic-server tsm-devices virtual-slave external-master-adapter
          slave-node-skeleton tsm-link)
    if(NOT EXISTS ${root}/usr/share/man/man1/${program}.1)
      message(FATAL_ERROR "man page not installed: ${program}.1")
    endif()
  endforeach()
endif()
if(LCM_JAVA)
  foreach(f usr/share/java/tsmh-lcmtypes.jar usr/bin/tsm-lcm-spy)
    if(NOT EXISTS ${root}/${f})
      message(FATAL_ERROR "not in the packages: ${f}")
    endif()
  endforeach()
endif()
file(GLOB_RECURSE config ${root}/usr/lib/*/tsmhConfig.cmake)
if(NOT config)
  message(FATAL_ERROR "tsmhConfig.cmake not in tsm-haptics-dev")
endif()
foreach(program tsm haptic-server tsm-devices virtual-slave external-master-adapter
          slave-node-skeleton tsm-link)
  run(${root}/usr/bin/${program} --version)
  if(NOT out MATCHES "^${program} \\(tsm-haptics\\) ${VERSION}\n$")
    message(FATAL_ERROR "extracted ${program} --version: ${out}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -E env --unset=TSMH_PROFILES_DIR ${root}/usr/bin/tsm-devices --help)
string(FIND "${out}" "${root}/usr/share/tsm-haptics/profiles" at)
if(at EQUAL -1)
  message(FATAL_ERROR "extracted tsm-devices does not default to the extracted profiles:\n${out}")
endif()
# The -dev package is usable from where it was extracted (the config is
# relocatable): the downstream project builds and runs against it.
build_downstream(${WORK_DIR}/downstream ${root}/usr)
message(STATUS "packages ok: ${runtime} ${dev}; downstream: ${out}")
