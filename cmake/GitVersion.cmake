# Generates build_info.cpp with the git commit, compiler and build type at every build; the file
# is rewritten only when its content changes, so an unchanged tree does not relink.
set(RKHS_BUILD_INFO_CPP ${CMAKE_BINARY_DIR}/generated/build_info.cpp)
add_custom_target(rkhs_build_info
  COMMAND ${CMAKE_COMMAND}
          -DSOURCE_DIR=${CMAKE_SOURCE_DIR}
          -DOUTPUT=${RKHS_BUILD_INFO_CPP}
          "-DCOMPILER=${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}"
          -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
          -DVERSION=${PROJECT_VERSION}
          -P ${CMAKE_SOURCE_DIR}/cmake/WriteBuildInfo.cmake
  BYPRODUCTS ${RKHS_BUILD_INFO_CPP}
  COMMENT "Recording build provenance"
  VERBATIM)
