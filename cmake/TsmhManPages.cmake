# Man pages generated from each program's --help and --version with help2man
# (Debian package help2man, scripts/deps.sh), into build/share/man/man1/ and
# installed to share/man/man1/. Skipped with a note when help2man is missing.
find_program(TSMH_HELP2MAN help2man)
set(TSMH_MAN_DIR ${CMAKE_BINARY_DIR}/${CMAKE_INSTALL_MANDIR}/man1)

# tsmh_man_page(target name "one-line description")
function(tsmh_man_page target name description)
  if(NOT TSMH_HELP2MAN)
    return()
  endif()
  set(page ${TSMH_MAN_DIR}/${name}.1)
  # --help shows defaults; the profile folder's is shown as installed.
  add_custom_command(OUTPUT ${page}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${TSMH_MAN_DIR}
    COMMAND ${CMAKE_COMMAND} -E env
      TSMH_PROFILES_DIR=${CMAKE_INSTALL_FULL_DATADIR}/tsm-haptics/profiles
      ${TSMH_HELP2MAN} --no-info --no-discard-stderr --section=1 --name=${description}
      --output=${page} $<TARGET_FILE:${target}>
    DEPENDS ${target}
    COMMENT "help2man: ${name}.1"
    VERBATIM)
  add_custom_target(${target}_man ALL DEPENDS ${page})
  install(FILES ${page} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)
endfunction()

if(TSMH_HELP2MAN)
  tsmh_man_page(haptic-server haptic-server "1 kHz haptic feedback server for tendon-sheath driven robots")
  tsmh_man_page(tsm tsm "tendon-sheath friction models: simulate, fit, gap, convert")
  tsmh_man_page(tsm-link tsm-link "the LCM link key: create it, tell which one a host uses")
  tsmh_man_page(tsm-devices tsm-devices "list and probe tsm-haptics master devices")
  tsmh_man_page(virtual_slave_app virtual-slave "virtual tendon-sheath slave with tissue, over LCM or offline")
  tsmh_man_page(external-master-adapter external-master-adapter
    "vendor master driver talking to haptic-server over LCM")
  tsmh_man_page(slave-node-skeleton slave-node-skeleton
    "minimal slave node of a real robot for haptic-server (robot I/O stubbed)")
else()
  message(STATUS "help2man not found: no man pages (scripts/deps.sh installs it)")
endif()
