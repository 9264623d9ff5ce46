# The exported CMake package (tsmhConfig.cmake, tsmhConfigVersion.cmake,
# tsmhTargets.cmake) and the docs. Included at the end of the top-level
# CMakeLists, after every module has added its targets to tsmhTargets.
include(CMakePackageConfigHelpers)
install(EXPORT tsmhTargets NAMESPACE tsmh:: DESTINATION ${TSMH_INSTALL_CMAKEDIR} COMPONENT dev)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/tsmhConfig.cmake.in
  ${CMAKE_BINARY_DIR}/tsmhConfig.cmake
  INSTALL_DESTINATION ${TSMH_INSTALL_CMAKEDIR}
  PATH_VARS TSMH_INSTALL_PROFILESDIR)
# 0.x: a minor release may break the API.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/tsmhConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/tsmhConfig.cmake ${CMAKE_BINARY_DIR}/tsmhConfigVersion.cmake
  DESTINATION ${TSMH_INSTALL_CMAKEDIR} COMPONENT dev)

install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${TSMH_INSTALL_DOCDIR} COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${TSMH_INSTALL_DOCDIR}/docs
  COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/examples/demo/server.yaml
  DESTINATION ${TSMH_INSTALL_DOCDIR}/examples/demo COMPONENT runtime)

# Debian packages (scripts/package; docs/install.md): `tsm-haptics` (programs,
# profiles, udev rules, docs) and `tsm-haptics-dev` (static libraries,
# headers, the CMake package), from the install components runtime and dev.
set(CPACK_PACKAGE_NAME tsm-haptics)
set(CPACK_PACKAGE_VENDOR "tsm-haptics")
set(CPACK_PACKAGE_CONTACT "tsm-haptics maintainers <tsm-haptics@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_GENERATOR DEB)
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME tsm-haptics)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION science)
# The programs' shared libraries (liblcm, libyaml-cpp, hidapi, libusb, nlopt,
# libstdc++ ...) are found by dpkg-shlibdeps; gnuplot draws `tsm` plots and
# lcm tools read the logs; tsm-lcm-spy needs a JRE, lcm.jar and jchart2d.
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "gnuplot-nox, default-jre, liblcm-java, libjchart2d-java")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SUGGESTS "liblcm-bin")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME tsm-haptics-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# The runtime package (tsmhConfig.cmake points at its profiles) and what
# tsmhConfig.cmake's find_dependency/pkg-config calls need.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
  "tsm-haptics (= ${PROJECT_VERSION}-${CPACK_DEBIAN_PACKAGE_RELEASE}), cmake, pkg-config, liblcm-dev, libyaml-cpp-dev, nlohmann-json3-dev, libnlopt-cxx-dev, libhidapi-dev, libusb-1.0-0-dev, libsodium-dev")
include(CPack)
