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
