# SPDX-License-Identifier: BSD-3-Clause
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

get_property(_modules GLOBAL PROPERTY NURBSFRONT_MODULES)
install(TARGETS ${_modules} EXPORT nurbsfrontTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY lib/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/nurbsfront
        FILES_MATCHING PATTERN "*.h")
install(EXPORT nurbsfrontTargets NAMESPACE nurbsfront::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/nurbsfront)
configure_package_config_file(cmake/nurbsfrontConfig.cmake.in
  "${PROJECT_BINARY_DIR}/nurbsfrontConfig.cmake"
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/nurbsfront)
write_basic_package_version_file("${PROJECT_BINARY_DIR}/nurbsfrontConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/nurbsfrontConfig.cmake"
              "${PROJECT_BINARY_DIR}/nurbsfrontConfigVersion.cmake"
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/nurbsfront)
