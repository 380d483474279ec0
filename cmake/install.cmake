# `make install` (cmake --install; PREFIX and DESTDIR honoured, see the Makefile): the tool, the
# static and the shared library, the public headers under include/cambium, the pkg-config file
# and the man page. Layout (GNUInstallDirs, relative to the prefix):
#   bin/cambium
#   lib/libcambium.a, lib/libcambium.so -> libcambium.so.0 -> libcambium.so.0.1.0
#   include/cambium/*.h
#   lib/pkgconfig/cambium.pc
#   share/man/man1/cambium.1
#   share/doc/cambium/examples/linking/ (the linking example of the README)
include(GNUInstallDirs)

install(TARGETS cambium_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS cambium cambium_shared
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/cambium
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
install(FILES ${PROJECT_SOURCE_DIR}/docs/cambium.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/linking
        DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)

# cambium.pc: the shared library by default; `pkg-config --static` adds what libcambium.a needs
# (the linked libraries of cmake/dependencies.cmake and libdl; Embree and cairo are loaded at run
# time, not linked). No Requires: the public headers include only the C library's, so a program
# needs no other package's flags (README, "Installing and linking"). The prefix is
# the one given at install time (`cmake --install --prefix`, `make install PREFIX=...`), so the
# file is finished by the install step itself.
set(CBM_PC_PREFIX "%PREFIX%")
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(CBM_PC_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
else()
  set(CBM_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(CBM_PC_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}")
else()
  set(CBM_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/cambium.pc.in ${PROJECT_BINARY_DIR}/cambium.pc.in @ONLY)
install(CODE "
  file(READ \"${PROJECT_BINARY_DIR}/cambium.pc.in\" pc)
  string(REPLACE \"%PREFIX%\" \"\${CMAKE_INSTALL_PREFIX}\" pc \"\${pc}\")
  file(WRITE \"${PROJECT_BINARY_DIR}/cambium.pc\" \"\${pc}\")")
install(FILES ${PROJECT_BINARY_DIR}/cambium.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
