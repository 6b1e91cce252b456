# Installation: headers under include/r1/, the r1 archive, the r1 command and a CMake package
# so another project can find_package(r1 CONFIG) and link r1::r1.
include(CMakePackageConfigHelpers)

install(DIRECTORY fixedpoint/include/ spec/include/ format/include/ solvers/include/ reference/include/ backends/include/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
# The frame renderer's headers, included as "render/NAME.hpp" (r1::render adds include/r1).
install(DIRECTORY reference/render/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/r1/render FILES_MATCHING PATTERN "*.hpp")
# Components: r1::r1 (core), r1::render (frame renderer), r1::backends (interface, registry,
# adapters, conformance harness) and, when RapidCheck was found, r1::conformance (the property
# library for backend authors, R1-TEST-050).
set(r1_installed_targets r1 r1_fixedpoint_headers r1_spec_headers r1_format_headers r1_solvers_headers r1_reference_headers r1_render r1_backends)
if(TARGET r1_conformance)
  list(APPEND r1_installed_targets r1_conformance)
endif()
install(TARGETS ${r1_installed_targets}
        EXPORT r1Targets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS r1_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT r1Targets NAMESPACE r1:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/r1)

configure_package_config_file(cmake/r1Config.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/r1Config.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/r1)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/r1ConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/r1Config.cmake ${CMAKE_CURRENT_BINARY_DIR}/r1ConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/r1)
