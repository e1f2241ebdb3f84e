# Installs the library layers as a CMake package (docs/install.md):
#   cmake --install build --prefix P
# puts the headers under P/include (rooted like the source tree: "validate/stats/tests.h",
# "estimators/mis.h", "lib/core/rng.h"), the static libraries under P/lib, and
# P/lib/cmake/testbench/{testbenchConfig,testbenchConfigVersion,testbenchTargets}.cmake, so that
# an outside project writes
#   find_package(testbench REQUIRED)
#   target_link_libraries(my_program PRIVATE testbench::validate)
# The exported targets are testbench::core, ::estimators, ::analytic, ::render and ::validate
# (tb_core ... tb_validate here; the same names exist as ALIAS targets in this build). The report
# layer, the registered checks and the tb program are not part of the package.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(TB_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/testbench" CACHE STRING
    "Where the package configuration files go, relative to the install prefix")
set(TB_EXPORTED_LAYERS tb_core tb_estimators tb_analytic tb_render tb_validate)

foreach(layer IN LISTS TB_EXPORTED_LAYERS)
  string(REGEX REPLACE "^tb_" "" short "${layer}")
  set_target_properties(${layer} PROPERTIES EXPORT_NAME ${short})
  add_library(testbench::${short} ALIAS ${layer})
  # Consumers need C++20 too (the headers use concepts); header-only layers carry it as well.
  get_target_property(type ${layer} TYPE)
  if(type STREQUAL "INTERFACE_LIBRARY")
    target_compile_features(${layer} INTERFACE cxx_std_20)
  else()
    target_compile_features(${layer} PUBLIC cxx_std_20)
  endif()
endforeach()

install(TARGETS ${TB_EXPORTED_LAYERS} EXPORT testbenchTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
# The headers of every exported layer, with their folder structure.
install(DIRECTORY lib estimators analytic validate
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development
        FILES_MATCHING PATTERN "*.h")
install(EXPORT testbenchTargets NAMESPACE testbench::
        DESTINATION ${TB_INSTALL_CMAKEDIR} COMPONENT development)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/testbenchConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/testbenchConfig.cmake
                              INSTALL_DESTINATION ${TB_INSTALL_CMAKEDIR})
# 0.x: a minor version may break the interface, so only the same major.minor is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/testbenchConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/testbenchConfig.cmake ${PROJECT_BINARY_DIR}/testbenchConfigVersion.cmake
        DESTINATION ${TB_INSTALL_CMAKEDIR} COMPONENT development)
