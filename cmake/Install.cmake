# Plugins and the installed package (docs/writing-a-kernel.md):
#   - rkhs/version.hpp, generated from the project version (plugins record what they were built
#     against);
#   - rkhs_study::plugin, the framework for plugin modules, and rkhs_study_add_plugin();
#   - `cmake --install` puts the public headers, librkhs_study.so, the rkhs-study command and the
#     CMake package rkhs_study (rkhs_studyConfig.cmake) under the prefix.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(RKHS_GENERATED_INCLUDE_DIR ${CMAKE_BINARY_DIR}/generated/include)
configure_file(${PROJECT_SOURCE_DIR}/cmake/version.hpp.in
               ${RKHS_GENERATED_INCLUDE_DIR}/rkhs/version.hpp @ONLY)
target_include_directories(rkhs_study PUBLIC
  $<BUILD_INTERFACE:${RKHS_GENERATED_INCLUDE_DIR}>
  $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
# dlopen (part of libc since glibc 2.34; CMAKE_DL_LIBS names libdl where it is separate).
target_link_libraries(rkhs_study PRIVATE ${CMAKE_DL_LIBS})

add_library(rkhs_study_plugin INTERFACE)
add_library(rkhs_study::plugin ALIAS rkhs_study_plugin)
target_link_libraries(rkhs_study_plugin INTERFACE rkhs_study)
target_compile_definitions(rkhs_study_plugin INTERFACE RKHS_BUILDING_PLUGIN)
# A plugin is compiled with this build's sanitizers, or the loader refuses it
# (plugin/build_configuration.hpp).
if(RKHS_STUDY_SANITIZE)
  target_compile_options(rkhs_study_plugin INTERFACE ${RKHS_SANITIZER_FLAGS})
  target_link_options(rkhs_study_plugin INTERFACE -fsanitize=${RKHS_STUDY_SANITIZE})
endif()
set_target_properties(rkhs_study_plugin PROPERTIES EXPORT_NAME plugin)
include(${PROJECT_SOURCE_DIR}/cmake/rkhs_studyPlugin.cmake)

# The installed command finds the installed library next to it, wherever the prefix is.
file(RELATIVE_PATH RKHS_BIN_TO_LIB ${CMAKE_INSTALL_FULL_BINDIR} ${CMAKE_INSTALL_FULL_LIBDIR})
set_target_properties(rkhs-study PROPERTIES INSTALL_RPATH "$ORIGIN/${RKHS_BIN_TO_LIB}")

install(TARGETS rkhs_study rkhs_study_plugin rkhs-study
        EXPORT rkhs_studyTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The public headers only: framework/include/ (the plugin API, the study and result types, and
# what they include) and the generated rkhs/version.hpp. framework/internal/, plugins/internal/ and
# framework/mpi/internal/ are not installed (plugins.install_and_build_example checks the list).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/framework/include/ ${RKHS_GENERATED_INCLUDE_DIR}/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp")

set(RKHS_PACKAGE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rkhs_study)
install(EXPORT rkhs_studyTargets NAMESPACE rkhs_study:: DESTINATION ${RKHS_PACKAGE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rkhs_studyConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/rkhs_studyConfig.cmake
                              INSTALL_DESTINATION ${RKHS_PACKAGE_DIR})
# Plugins check their ABI at load time; the package version only has to agree on major.minor.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/rkhs_studyConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/rkhs_studyConfig.cmake
              ${CMAKE_BINARY_DIR}/rkhs_studyConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/rkhs_studyPlugin.cmake
        DESTINATION ${RKHS_PACKAGE_DIR})
