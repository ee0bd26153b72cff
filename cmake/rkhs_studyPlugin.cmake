# rkhs_study_add_plugin(<target> <source>...)
#
# Builds an rkhs-study plugin module <target>.so (no "lib" prefix) from the sources: a MODULE
# library linked against rkhs_study::plugin, i.e. against librkhs_study with RKHS_BUILDING_PLUGIN
# defined, so that RKHS_REGISTER_KERNEL waits for the loader's ABI check (rkhs/plugin/module.hpp).
# Symbols are hidden except the module's extern "C" entry points (RKHS_PLUGIN_MODULE), so two
# plugins never see each other's code.
function(rkhs_study_add_plugin target)
  if(NOT ARGN)
    message(FATAL_ERROR "rkhs_study_add_plugin(${target}): no source files")
  endif()
  add_library(${target} MODULE ${ARGN})
  target_link_libraries(${target} PRIVATE rkhs_study::plugin)
  set_target_properties(${target} PROPERTIES
    PREFIX ""
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
endfunction()
