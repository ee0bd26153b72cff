#!/usr/bin/env bash
# The installed package, as a plugin author uses it (the steps of docs/writing-a-kernel.md): install
# this build into a temporary prefix, check that its include/rkhs/ holds exactly the public headers
# (framework/include/rkhs/ and the generated version.hpp; nothing of an internal/ folder) and that
# each of them includes only installed headers, build examples/kernel-plugin out of tree against it
# (find_package(rkhs_study)), list its kernel, run `verify-plugin` on the result, and run the
# example's study with the plugin loaded through `plugins = [...]`, `--plugin` and
# RKHS_STUDY_PLUGIN_PATH. With tests/docs/check_tutorial_snippets.py (every code block of the
# page is an excerpt of these files) it makes the page's code compile.
#
# The plugin is compiled by CXX_COMPILER, the compiler of the build (the loader refuses a plugin
# built by another compiler family or version, plugin/build_configuration.hpp). Then the same
# plugin is built once more with -mavx where the build is for generic x86-64 and the processor has
# AVX: the installed rkhs-study refuses it, naming both configurations.
#
# An embedding program (tests/plugin/embedding/) is built out of tree against the package too, with
# one source that includes every installed header, and runs a small study.
#
# Last, the console excerpts of docs/writing-a-kernel.md are compared with what this package prints
# for the plugin (tests/docs/check_console_excerpts.py), also after the page's "Try lying" edit.
#
# Usage: install_and_build_plugin.sh BUILD_DIR SOURCE_DIR [CMAKE [CXX_COMPILER [PYTHON]]]
set -euo pipefail
build=$1
source=$2
cmake=${3:-cmake}
compiler=()
[[ -n ${4:-} ]] && compiler=(-DCMAKE_CXX_COMPILER="$4")
python=${5:-python3}
work=$(mktemp -d "${TMPDIR:-/tmp}/rkhs_install_test.XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

step() { echo "== $*"; }
fail() { echo "FAILED: $*" >&2; exit 1; }

step "cmake --install into $prefix"
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log"
rkhs=$prefix/bin/rkhs-study
[[ -x $rkhs ]] || fail "no $rkhs"
for header in rkhs/plugin/module.hpp rkhs/kernel/kernel_algorithms.hpp rkhs/version.hpp \
              rkhs/study/study.hpp rkhs/run/run.hpp; do
  [[ -f $prefix/include/$header ]] || fail "header $header not installed"
done

step "include/rkhs/ holds exactly the public headers, and they include only installed headers"
# The public headers: every file of framework/include/rkhs/, and version.hpp (generated).
{ (cd "$source/framework/include" && find rkhs -type f); echo rkhs/version.hpp; } | LC_ALL=C sort > "$work/public.txt"
(cd "$prefix/include" && find rkhs -type f) | LC_ALL=C sort > "$work/installed.txt"
[[ $(wc -l < "$work/public.txt") -gt 10 ]] || fail "no public headers found below $source/framework/include"
if ! diff -u --label "public headers (framework/include/rkhs/)" --label "installed ($prefix/include/rkhs/)" \
     "$work/public.txt" "$work/installed.txt" > "$work/headers.diff"; then
  cat "$work/headers.diff"
  fail "the installed headers are not the public ones (an internal header installed, or a public one missing)"
fi
missing=0
while read -r header; do
  while read -r included; do
    [[ -f $prefix/include/$included ]] && continue
    echo "$header includes $included, which is not installed (an internal header?)"
    missing=1
  done < <(sed -n 's|^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]\(rkhs/[^">]*\)[">].*|\1|p' "$prefix/include/$header")
done < "$work/installed.txt"
[[ $missing == 0 ]] || fail "an installed header includes a header that is not installed"
config=$(find "$prefix" -name rkhs_studyConfig.cmake)
[[ -n $config ]] || fail "rkhs_studyConfig.cmake not installed"
# The installed command uses the installed library (its RUNPATH), not the build tree's.
# (ldd's output is captured first: `ldd | grep -q` under pipefail fails when grep exits early.)
linked=$(ldd "$rkhs")
grep -q "$prefix/.*librkhs_study.so" <<<"$linked" || fail "rkhs-study does not find $prefix's library: $(grep rkhs <<<"$linked")"

step "build examples/kernel-plugin out of tree against the prefix"
cp -r "$source/examples/kernel-plugin" "$work/kernel-plugin"
rm -rf "$work/kernel-plugin/build"
generator=()
command -v ninja > /dev/null && generator=(-G Ninja)
"$cmake" -S "$work/kernel-plugin" -B "$work/kernel-plugin/build" "${generator[@]}" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" "${compiler[@]}" > "$work/configure.log" \
  || { cat "$work/configure.log"; fail "configure"; }
"$cmake" --build "$work/kernel-plugin/build" -j 2 > "$work/build.log" || { cat "$work/build.log"; fail "build"; }
plugin=$work/kernel-plugin/build/inverse_multiquadric.so
[[ -f $plugin ]] || fail "no $plugin"

step "build and run an embedding program out of tree, with every installed header compiled"
cp -r "$source/tests/plugin/embedding" "$work/embedding"
rm -rf "$work/embedding/build"
sed 's|^\(.*\)$|#include "\1"|' "$work/installed.txt" > "$work/embedding/all_public_headers.cpp"
"$cmake" -S "$work/embedding" -B "$work/embedding/build" "${generator[@]}" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" "${compiler[@]}" > "$work/configure-embedding.log" \
  || { cat "$work/configure-embedding.log"; fail "configure the embedding program"; }
"$cmake" --build "$work/embedding/build" -j 2 > "$work/build-embedding.log" \
  || { cat "$work/build-embedding.log"; fail "build the embedding program and every installed header"; }
"$work/embedding/build/embed_study" | tee "$work/embedding.txt"
grep -q "^embedded study: 2 trials ok$" "$work/embedding.txt" || fail "the embedding program's study did not run"

step "list kernel --plugin"
"$rkhs" list kernel --plugin "$plugin" > "$work/list.txt"
grep -q "^  inverse_multiquadric inverse multiquadric" "$work/list.txt" || { cat "$work/list.txt"; fail "list kernel does not show the plugin's kernel"; }
grep -q "^    beta  *exponent beta" "$work/list.txt" || fail "list kernel does not show the parameter beta"

step "verify-plugin"
"$rkhs" verify-plugin "$plugin" | tee "$work/verify.txt"
grep -q "^verify-plugin: PASS" "$work/verify.txt" || fail "verify-plugin did not pass"

step "run the example study (plugins = [...] relative to the study file)"
cd "$work"  # not the study's directory: the plugin path must be resolved against the file
"$rkhs" run kernel-plugin/imq_study.toml --out "$work/out" --threads 2 --quiet
grep -q "^inverse_multiquadric,1,1," "$work/out/trials.csv" || fail "no inverse_multiquadric trials in trials.csv"
if grep -q ",failed," "$work/out/trials.csv"; then fail "failed trials"; fi

step "the constructor refuses beta <= 1/2 on the closed track while the study is read"
sed 's/^beta = \[1, 2\]$/beta = 0.5/' kernel-plugin/imq_study.toml > kernel-plugin/bad_beta.toml
grep -q "^beta = 0.5$" kernel-plugin/bad_beta.toml || fail "imq_study.toml has no line 'beta = [1, 2]'"
status=0
"$rkhs" validate kernel-plugin/bad_beta.toml > "$work/bad_beta.txt" 2>&1 || status=$?
[[ $status == 2 ]] || { cat "$work/bad_beta.txt"; fail "validate with beta = 0.5 exited $status, not 2"; }
grep -q "bad_beta.toml:21:8: kernel.beta: inverse_multiquadric beta=0.5 c=1: parameter 'beta' must be > 1/2 on a closed track" "$work/bad_beta.txt" \
  || { cat "$work/bad_beta.txt"; fail "no file:line:column message naming beta"; }

step "--plugin and RKHS_STUDY_PLUGIN_PATH"
grep -v '^plugins' kernel-plugin/imq_study.toml > "$work/no_plugins_key.toml"
"$rkhs" validate "$work/no_plugins_key.toml" > /dev/null 2>&1 && fail "the kernel is known without its plugin"
"$rkhs" validate --plugin "$plugin" "$work/no_plugins_key.toml"
RKHS_STUDY_PLUGIN_PATH=$work/kernel-plugin/build "$rkhs" validate "$work/no_plugins_key.toml"
step "the same plugin built with -mavx is refused, naming both configurations"
if grep -q "SSE2" <<<"$("$rkhs" verify-plugin "$plugin" 2>&1)" && grep -qw avx /proc/cpuinfo; then
  "$cmake" -S "$work/kernel-plugin" -B "$work/kernel-plugin/build-avx" "${generator[@]}" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" "${compiler[@]}" \
    -DCMAKE_CXX_FLAGS=-mavx > "$work/configure-avx.log" || { cat "$work/configure-avx.log"; fail "configure -mavx"; }
  "$cmake" --build "$work/kernel-plugin/build-avx" -j 2 > "$work/build-avx.log" || { cat "$work/build-avx.log"; fail "build -mavx"; }
  status=0
  "$rkhs" verify-plugin "$work/kernel-plugin/build-avx/inverse_multiquadric.so" > "$work/avx.txt" 2>&1 || status=$?
  [[ $status != 0 ]] || { cat "$work/avx.txt"; fail "the -mavx plugin was accepted"; }
  grep -q "built for .*AVX.*, this rkhs-study is built for .*SSE2.*; vectorisation AVX against SSE2)" "$work/avx.txt" \
    || { cat "$work/avx.txt"; fail "the refusal does not name both configurations"; }
  cat "$work/avx.txt"
else
  echo "(skipped: this build is not for generic x86-64 with SSE2, or the processor has no AVX)"
fi
step "docs/writing-a-kernel.md's console excerpts against this package and plugin"
# The page shows the output of a release build (its `built for` line); another build (clang, a
# sanitizer) prints other configuration lines, so the page is compared only where they agree.
checker=("${python}" "$source/tests/docs/check_console_excerpts.py" "$rkhs" "$source/docs/writing-a-kernel.md"
         "$work/kernel-plugin" "$work/console" --replace "/home/you/kernel-plugin=$(cd "$work/kernel-plugin" && pwd -P)")
page_build=$(grep -m1 "^  built for " "$source/docs/writing-a-kernel.md" || true)
this_build=$(grep -m1 "^  built for " "$work/verify.txt" || true)
if [[ $page_build == "$this_build" ]]; then
  "${checker[@]}" || fail "docs/writing-a-kernel.md's console excerpts do not match the output"
  # "Try lying" (section 9): declare a Sobolev order instead of analyticity and rebuild.
  sed -i 's/^  p.analytic = true;  /  p.sobolev_order = 3.0;/' "$work/kernel-plugin/inverse_multiquadric.cpp"
  grep -q "^  p.sobolev_order = 3.0;" "$work/kernel-plugin/inverse_multiquadric.cpp" \
    || fail "inverse_multiquadric.cpp has no line 'p.analytic = true;' for the page's lie"
  "$cmake" --build "$work/kernel-plugin/build" -j 2 > "$work/build-lie.log" || { cat "$work/build-lie.log"; fail "build the lie"; }
  "${checker[@]}" --variant lying || fail "the page's 'Try lying' excerpt does not match the output"
else
  echo "(skipped: this build prints '${this_build# *}', the page shows '${page_build# *}')"
fi
echo "installed package (public headers only), out-of-tree plugin and embedding program, verify-plugin, study and tutorial console: ok"
