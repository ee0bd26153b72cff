#!/usr/bin/env bash
# The layer check of framework/CMakeLists.txt at work: every layer's objects are linked into a
# shared library of their own against the layers below only, with --no-undefined, so a lower
# layer that calls a definition of a higher one fails the build. Here a call into the plugin
# layer (registration_errors(), plugin/registry.cpp) is linked the same way twice:
#   - as the core layer would be, against core's check library: the link must fail, naming it;
#   - as the pipeline layer would be, against every layer's: the link must succeed.
# And each layer of RKHS_LAYERS must have its check library in LAYER_CHECK_DIR.
#
# Usage: check_layer_link.sh CXX LAYER_CHECK_DIR WORK_DIR "LAYER;LAYER;..."
set -euo pipefail
cxx=$1
dir=$2
work=$3
IFS=';' read -r -a layers <<<"$4"
mkdir -p "$work"
fail() { echo "FAILED: $*" >&2; exit 1; }

for layer in "${layers[@]}"; do
  [[ -f $dir/librkhs_layer_check_$layer.so ]] || fail "no check library for layer $layer in $dir"
done

cat > "$work/upward.cpp" <<'CPP'
#include <cstddef>
#include <string>
#include <vector>
namespace rkhs {
std::vector<std::string> registration_errors();  // defined in the plugin layer
std::size_t upward_call() { return registration_errors().size(); }
}  // namespace rkhs
CPP
"$cxx" -std=c++20 -fPIC -c "$work/upward.cpp" -o "$work/upward.o"

link() {  # link LIBRARIES...: upward.o as a shared library against the named check libraries
  "$cxx" -shared -o "$work/upward.so" "$work/upward.o" -Wl,--no-undefined -L"$dir" \
    -Wl,-rpath-link,"$dir" "${@/#/-lrkhs_layer_check_}"
}

if link core > "$work/core.log" 2>&1; then
  fail "a call from the core layer into the plugin layer linked against the core layer alone"
fi
grep -q "undefined reference to .rkhs::registration_errors" "$work/core.log" \
  || { cat "$work/core.log"; fail "the failed link does not name the upward call"; }
link "${layers[@]}" > "$work/all.log" 2>&1 || { cat "$work/all.log"; fail "the call does not link against every layer"; }
echo "layer check: an upward call fails its layer's link, and links against the layers above (${#layers[@]} layers)"
