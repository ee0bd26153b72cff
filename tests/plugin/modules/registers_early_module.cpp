// The module's entry points, compiled as a plugin (see registers_early_kernel.cpp).
#include "rkhs/plugin/module.hpp"

RKHS_PLUGIN_MODULE("registers_early")
