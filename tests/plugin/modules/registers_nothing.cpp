// A well-formed module that forgot RKHS_REGISTER_KERNEL.
#include "rkhs/plugin/module.hpp"

RKHS_PLUGIN_MODULE("registers_nothing")
