# install.cmake — `cmake --install build --prefix PREFIX` puts:
#   bin/                          truss-sim, truss-campaign
#   lib/                          the static libraries (truss_core, truss_io, truss_util,
#                                 truss_statistics, truss_sampling, truss_campaign, truss_results,
#                                 truss_methods, truss_parallel)
#   include/truss_deploy/         the public headers, by folder (#include "sim/simulate.hpp")
#   lib/cmake/truss_deploy/       package config: find_package(truss_deploy) gives the imported
#                                 targets truss_deploy::truss_core, ::truss_io, ::truss_util,
#                                 ::truss_statistics, ::truss_sampling, ::truss_campaign, ::truss_results,
#                                 ::truss_methods, ::truss_parallel, ::truss_model
#   share/man/man1/               truss-sim.1, truss-campaign.1 (help2man, from --help, at install)
#   share/truss_deploy/campaigns/ the shipped scene and campaign files
# Included from the top-level CMakeLists.txt after every target is defined.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(TRUSS_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/truss_deploy)
set(TRUSS_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/truss_deploy)

install(TARGETS truss_model truss_core truss_io truss_util truss_statistics truss_sampling truss_campaign truss_results
                truss_methods truss_parallel
        EXPORT truss_deployTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${TRUSS_INSTALL_INCLUDEDIR})  # installed targets find their headers here
install(TARGETS truss-sim truss-campaign RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${CMAKE_SOURCE_DIR}/src/ DESTINATION ${TRUSS_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp"
        PATTERN "app" EXCLUDE)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/campaigns/ DESTINATION ${CMAKE_INSTALL_DATADIR}/truss_deploy/campaigns)

install(EXPORT truss_deployTargets NAMESPACE truss_deploy:: DESTINATION ${TRUSS_INSTALL_CMAKEDIR})
configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/truss_deployConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/truss_deployConfig.cmake
                              INSTALL_DESTINATION ${TRUSS_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/truss_deployConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/truss_deployConfig.cmake ${CMAKE_BINARY_DIR}/truss_deployConfigVersion.cmake
        DESTINATION ${TRUSS_INSTALL_CMAKEDIR})

# Man pages from each program's --help (Debian package help2man, in scripts/install-deps.sh),
# written at install time from the installed programs: an install needs nothing beyond the two
# programs and the libraries, whatever targets the build made (scripts/run_main.sh builds only the
# programs; ctest install_after_main checks that such a build installs).
find_program(HELP2MAN_EXECUTABLE help2man)
if(HELP2MAN_EXECUTABLE)
  foreach(prog truss-sim truss-campaign)
    if(prog STREQUAL "truss-sim")
      set(summary "simulate one deployment or retraction of a folding truss mast")
    else()
      set(summary "run an MPI uncertainty campaign of truss mast deployments into one HDF5 file")
    endif()
    # --version-string: help2man would otherwise run `prog --version`; the version is the project's.
    # OMPI_MCA_btl=self: truss-campaign --help runs as an MPI singleton; no network is needed.
    install(CODE "
      set(man_dir \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_MANDIR}/man1\")
      file(MAKE_DIRECTORY \"\${man_dir}\")
      message(STATUS \"Installing: \${man_dir}/${prog}.1 (help2man)\")
      execute_process(COMMAND \"${CMAKE_COMMAND}\" -E env OMPI_MCA_btl=self \"${HELP2MAN_EXECUTABLE}\"
                              --no-info --no-discard-stderr \"--name=${summary}\"
                              --version-string=${PROJECT_VERSION} --section=1 \"--output=\${man_dir}/${prog}.1\"
                              \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_BINDIR}/${prog}\"
                      RESULT_VARIABLE rc)
      if(NOT rc EQUAL 0)
        message(FATAL_ERROR \"help2man ${prog}: exit \${rc}\")
      endif()
      list(APPEND CMAKE_INSTALL_MANIFEST_FILES \"\${man_dir}/${prog}.1\")
    ")
  endforeach()
else()
  message(STATUS "help2man not found: no man pages (apt-get install help2man, or scripts/install-deps.sh)")
endif()
