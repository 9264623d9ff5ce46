# Install layout (FHS via GNUInstallDirs; the prefix is CMAKE_INSTALL_PREFIX,
# or `cmake --install build --prefix DIR`) and the helpers every module uses
# to put its targets into the exported package (docs/install.md):
#
#   bin/                          tsm, tsm-link, haptic-server, tsm-devices, virtual-slave,
#                                 external-master-adapter, slave-node-skeleton, tsm-lcm-spy
#   lib/<multiarch>/              static libraries libtsmh_*.a
#   lib/<multiarch>/cmake/tsmh/   tsmhConfig.cmake, tsmhConfigVersion.cmake, targets
#   include/tsmh/                 estimator/ bridge/ haptics/ master_devices/ tsmh/ headers
#   share/tsm-haptics/profiles/   device profiles (found relative to bin/)
#   share/doc/tsm-haptics/        README and docs/
#   lib/udev/rules.d/             70-tsm-haptics.rules
include(GNUInstallDirs)

# Headers live under include/tsmh/ so that `estimator/`, `bridge/` etc. do not
# land directly in /usr/include.
set(TSMH_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/tsmh)
set(TSMH_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/tsmh)
set(TSMH_INSTALL_PROFILESDIR ${CMAKE_INSTALL_DATADIR}/tsm-haptics/profiles)
set(TSMH_INSTALL_DOCDIR ${CMAKE_INSTALL_DATADIR}/doc/tsm-haptics)
# Relative to the prefix; Debian's udev reads /lib/udev/rules.d and
# /usr/lib/udev/rules.d (not /usr/local: copy to /etc/udev/rules.d there).
set(TSMH_INSTALL_UDEVRULESDIR lib/udev/rules.d CACHE STRING
    "Where the udev rules are installed (relative to the prefix, or absolute)")

# tsmh_install_library(target [header_dir]): installs the library into the
# tsmhTargets export set (as tsmh::<target>, file libtsmh_<target>.a) and, if
# given, its header folder.
function(tsmh_install_library target)
  get_target_property(type ${target} TYPE)
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    # libtsmh_<name>.a, not a generic libbridge.a in /usr/lib; PIC so that a
    # downstream shared library can link the static archives.
    set_target_properties(${target} PROPERTIES OUTPUT_NAME tsmh_${target}
      POSITION_INDEPENDENT_CODE ON)
  endif()
  install(TARGETS ${target} EXPORT tsmhTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
  if(ARGC GREATER 1)
    install(DIRECTORY ${ARGV1} DESTINATION ${TSMH_INSTALL_INCLUDEDIR} COMPONENT dev
      FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
  endif()
endfunction()

# tsmh_add_library(target ALIAS module::name [INCLUDE_DIR dir] [HEADERS folder]
#                  SOURCES src...): one of the project's libraries, written
# once: its sources; the names it is linked by, its module's `module::name`
# and the package's tsmh::<target>; `dir` (default: the module's include/)
# as its public include directory (the installed include/tsmh/ once
# installed); the project's warnings; and its install, with the header folder
# dir/folder when given (tsmh_install_library).
function(tsmh_add_library target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "ALIAS;INCLUDE_DIR;HEADERS" "SOURCES")
  if(NOT arg_INCLUDE_DIR)
    set(arg_INCLUDE_DIR ${CMAKE_CURRENT_SOURCE_DIR}/include)
  endif()
  add_library(${target} ${arg_SOURCES})
  add_library(${arg_ALIAS} ALIAS ${target})
  add_library(tsmh::${target} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${arg_INCLUDE_DIR}>
    $<INSTALL_INTERFACE:${TSMH_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:tsmh::warnings>)
  if(arg_HEADERS)
    tsmh_install_library(${target} ${arg_INCLUDE_DIR}/${arg_HEADERS})
  else()
    tsmh_install_library(${target})
  endif()
endfunction()

# tsmh_install_programs(target...): installs executables into bin/.
function(tsmh_install_programs)
  install(TARGETS ${ARGN} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
endfunction()

# tsmh::version: the generated tsmh/version.hpp (project version, one place).
set(TSMH_GENERATED_INCLUDE_DIR ${CMAKE_BINARY_DIR}/generated/include)
configure_file(${CMAKE_CURRENT_LIST_DIR}/version.hpp.in ${TSMH_GENERATED_INCLUDE_DIR}/tsmh/version.hpp
  @ONLY)
add_library(tsmh_version INTERFACE)
add_library(tsmh::version ALIAS tsmh_version)
set_target_properties(tsmh_version PROPERTIES EXPORT_NAME version)
target_include_directories(tsmh_version INTERFACE $<BUILD_INTERFACE:${TSMH_GENERATED_INCLUDE_DIR}>
  $<INSTALL_INTERFACE:${TSMH_INSTALL_INCLUDEDIR}>)
tsmh_install_library(tsmh_version)
install(FILES ${TSMH_GENERATED_INCLUDE_DIR}/tsmh/version.hpp
  DESTINATION ${TSMH_INSTALL_INCLUDEDIR}/tsmh COMPONENT dev)
