#!/usr/bin/env bash
# ctest -L install: install.consumer (tests/install/CMakeLists.txt). What an engine developer does
# with Penumbra, checked from outside the build tree:
#   1. cmake --install of the build tree into a fresh prefix, its tools and libraries stripped;
#   2. include/ holds penumbra/ and nothing else, and every installed header includes its siblings
#      as <penumbra/...> (no quoted includes); every public header of the GL-free components
#      (adaptive, psychometrics, study_log; shaders/virtual_mark_contract.h, the page marking's),
#      with include/ alone on the include path, includes nothing but other installed headers and
#      the C and C++ standard libraries, and compiles at the C++ standard its target asks for (17;
#      psychometrics 20);
#      share/penumbra/shaders/virtual_mark.comp is the build's, with no #include or #version left;
#   3. a call to required_texels_ws with the light's extent and the filter radius swapped (or
#      given as bare numbers) fails to compile, the right one compiles;
#   4. tests/install/consumer (and examples/engine_integration through it) configures with
#      find_package(Penumbra CONFIG REQUIRED), checks what each target links, builds and runs;
#      examples/engine_integration refuses a calibration entry marked unusable (one line, exit 1)
#      unless given --allow-unusable, and prints the fitter's flags and NOT USABLE on its c line;
#   5. the rule's check and the example build with pkg-config penumbra-adaptive alone, and run;
#   6. every installed tool prints its version, and its --help names the installed docs page; the
#      installed tools find the installed calibration and study configs.
# usage: consumer_test.sh BUILD_DIR SOURCE_DIR WORK_DIR CXX_COMPILER VERSION
set -euo pipefail
build=$1 source=$2 work=$3 cxx=$4 version=$5
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
start=$SECONDS
step() { echo "== [$((SECONDS - start)) s] $*"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

step "cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
include=$prefix/include
[[ -f $include/penumbra/adaptive/resolution_rule.h ]] || fail "no adaptive/resolution_rule.h under $include/penumbra"

step "installed stripped: no debug information in the tools or the libraries"
# cmake --install strips without --strip (PENUMBRA_INSTALL_STRIP, cmake/Install.cmake), unless the
# build was configured not to.
if grep -q '^PENUMBRA_INSTALL_STRIP:BOOL=ON$' "$build/CMakeCache.txt"; then
  for f in "$prefix"/bin/* "$prefix"/lib/libpenumbra_*.a; do
    ! readelf -S --wide "$f" 2>/dev/null | grep -q '[[:space:]]\.debug_info[[:space:]]' || fail "$f keeps its debug information"
  done
  echo "$(ls "$prefix"/bin | wc -l) tools and $(ls "$prefix"/lib/libpenumbra_*.a | wc -l) libraries without .debug_info; the prefix: $(du -sk "$prefix" | cut -f1) KiB"
else
  echo "PENUMBRA_INSTALL_STRIP is off: not checked"
fi

step "include/: penumbra/ alone, its headers included as <penumbra/...>"
# What an engine puts on its include path is include/: anything beside penumbra/ would land there
# (a log/, gl/ or published.h of Penumbra's beside the engine's own).
others=$(cd "$include" && find . -mindepth 1 -maxdepth 1 ! -name penumbra -printf '%P ')
[[ -z $others ]] || fail "include/ holds more than penumbra/: $others"
# A quoted include would find a sibling by its short name (the including file's directory first).
quoted=$(grep -rn '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$include/penumbra" || true)
[[ -z $quoted ]] || fail "installed headers include by a short name, not <penumbra/...>: $quoted"
# Nor by an angle-bracket name of its own tree without the prefix (<adaptive/...>, <published.h>).
names=$(cd "$include/penumbra" && { find . -mindepth 1 -maxdepth 1 -type d -printf '%P/\n'; find . -mindepth 1 -maxdepth 1 -type f -printf '%P>\n'; } |
  sed 's/[.]/[.]/g' | paste -sd'|')
short=$(grep -rnE "^[[:space:]]*#[[:space:]]*include[[:space:]]*<($names)" "$include/penumbra" || true)
[[ -z $short ]] || fail "installed headers include a sibling without penumbra/: $short"

step "GL-free public headers: what they include, and that they compile (include/ alone)"
# What a header may reach: installed headers, libstdc++, GCC's own headers, libc.
allowed="^($include/penumbra/|/usr/include/c\+\+/|/usr/include/[^/]*-linux-gnu/c\+\+/|/usr/lib/gcc/|/usr/include/[^/]+\.h$|/usr/include/[^/]*-linux-gnu/(bits|sys|gnu|asm)/|/usr/include/(linux|asm-generic)/)"
headers=$(cd "$include" && ls penumbra/published.h penumbra/sampling/random.h penumbra/adaptive/*.h penumbra/quest/*.h \
  penumbra/log/*.h penumbra/observers/observer.h penumbra/observers/psychometric_observer.h penumbra/observers/staircase_simulation.h \
  penumbra/shaders/virtual_mark_contract.h)
for h in $headers; do
  echo "#include <$h>" >"$work/header.cpp"
  # The files it includes, one per line (-M: preprocessing only, so a header not installed fails here).
  "$cxx" -std=c++20 -M -I"$include" "$work/header.cpp" >"$work/header.d" ||
    fail "$h includes a header that is not installed"
  # shellcheck disable=SC2046  # one word per file
  outside=$(realpath -m -- $(sed -e 's/^[^:]*://' -e 's/\\$//' "$work/header.d") | grep -v -e 'header.cpp$' | grep -Ev "$allowed" || true)
  [[ -z $outside ]] || fail "$h includes $outside (neither Penumbra's installed headers nor the standard library)"
  standard=c++17
  [[ $h == penumbra/quest/* || $h == penumbra/observers/* ]] && standard=c++20
  echo "#include <$h>" >>"$work/headers-$standard.cpp"
done
for standard in c++17 c++20; do
  "$cxx" -std=$standard -Wall -Wextra -Wpedantic -Werror -fsyntax-only -I"$include" "$work/headers-$standard.cpp" ||
    fail "the headers of $work/headers-$standard.cpp do not compile as $standard"
done
echo "$(wc -w <<<"$headers") headers"

step "share/penumbra/shaders: the page marking for engines, its includes inlined"
# GLSL has no #include: an engine's loader compiles the file as it is (test_virtual_mark_gl compiles it
# on the driver from the build tree; here: the installed copy is that file).
mark=$prefix/share/penumbra/shaders/virtual_mark.comp
[[ -f $mark ]] || fail "no $mark"
cmp -s "$mark" "$build/install/shaders/virtual_mark.comp" || fail "$mark is not the build's install/shaders/virtual_mark.comp"
! grep -nE '^[[:space:]]*#[[:space:]]*(include[[:space:]]*"|version)' "$mark" || fail "$mark has an #include to expand or a #version of its own"
echo "$mark: $(wc -l <"$mark") lines"

step "required_texels_ws: the light's extent and the filter radius cannot be swapped (try-compiles that must fail)"
# Both are world-space lengths; the rule takes them as LightExtentWs and FilterRadiusWs, whose
# constructors are explicit. Each call below must fail to compile; the first, in the right order,
# must compile (so the others fail for their arguments, not for the setup).
calls=("required_texels_ws(3.47, LightExtentWs{20.0}, FilterRadiusWs{0.05})"
       "required_texels_ws(3.47, FilterRadiusWs{0.05}, LightExtentWs{20.0})"
       "required_texels_ws(3.47, 0.05, 20.0)"
       "required_texels_ws(3.47, {0.05}, {20.0})"
       "required_texels_uv(3.47, 0.05)"
       "required_texels_uv(3.47, FilterRadiusWs{0.05})")
for i in "${!calls[@]}"; do
  printf '#include <penumbra/adaptive/resolution_rule.h>\nusing namespace penumbra::adaptive;\ndouble f() { return %s; }\n' "${calls[i]}" >"$work/call-$i.cpp"
  if "$cxx" -std=c++17 -fsyntax-only -I"$include" "$work/call-$i.cpp" 2>"$work/call-$i.log"; then
    ((i == 0)) || fail "compiles, and must not (the rule's arguments can be swapped or given bare): ${calls[i]}"
  else
    ((i != 0)) || { cat "$work/call-$i.log"; fail "does not compile: ${calls[i]}"; }
  fi
done
echo "$((${#calls[@]} - 1)) calls refused by the compiler: ${calls[*]:1}"

step "find_package(Penumbra CONFIG REQUIRED): tests/install/consumer and examples/engine_integration"
cmake -S "$source/tests/install/consumer" -B "$work/consumer" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DEXPECTED_PREFIX="$prefix" -DEXAMPLE_DIR="$source/examples/engine_integration" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF >"$work/consumer-configure.log" || { cat "$work/consumer-configure.log"; fail "configure"; }
grep -- "-- Penumbra::" "$work/consumer-configure.log"
cmake --build "$work/consumer" -j 1 >"$work/consumer-build.log" || { cat "$work/consumer-build.log"; fail "build"; }
"$work/consumer/size_shadow_map" "$prefix/share/penumbra/calibration/default.json"
"$work/consumer/quest_and_log" "$work"
"$work/consumer/renderer_link"
"$work/consumer/example/engine_integration" "$prefix/share/penumbra/calibration/default.json" >"$work/example.txt"
head -2 "$work/example.txt"
grep -q "^frame 63 " "$work/example.txt" || fail "engine_integration stopped before frame 63"

step "engine_integration: an unusable entry is refused (one line, exit 1) unless --allow-unusable; flags are printed"
# A pilot fit written with penumbra-fit --allow-unusable: c = 0.03 would size every map at the
# smallest resolution the limits allow.
example=$work/consumer/example/engine_integration
printf '%s\n' '{"schema_version": 2, "entries": [{"technique": "pcf", "kernel": "grid", "c": 0.03, "obtained_by": "study",' \
  '  "participants": 1, "flags": ["one_participant"], "usable": false, "unusable_because": ["interval_open", "c_outside_0.5_20"]}]}' \
  >"$work/unusable.json"
status=0
"$example" "$work/unusable.json" >"$work/unusable.out" 2>"$work/unusable.err" || status=$?
((status == 1)) || fail "engine_integration with an unusable entry exited $status, not 1"
[[ ! -s $work/unusable.out && $(wc -l <"$work/unusable.err") -eq 1 ]] ||
  fail "engine_integration with an unusable entry: not one line on stderr and nothing else: $(cat "$work/unusable.out" "$work/unusable.err")"
grep -q "^engine_integration: $work/unusable.json: the pcf grid entry has \"usable\": false (interval_open, c_outside_0.5_20): .*--allow-unusable" \
  "$work/unusable.err" || fail "engine_integration's refusal names neither the file, the entry nor the reasons: $(cat "$work/unusable.err")"
cat "$work/unusable.err"
"$example" --allow-unusable "$work/unusable.json" >"$work/allowed.out" || fail "engine_integration --allow-unusable with an unusable entry"
head -1 "$work/allowed.out"
head -1 "$work/allowed.out" | grep -q "^c = 0.03 texels (.*); NOT USABLE: interval_open, c_outside_0.5_20; flags: one_participant$" ||
  fail "engine_integration --allow-unusable does not say NOT USABLE and the flags on its c line"
grep -q "^frame 63 " "$work/allowed.out" || fail "engine_integration --allow-unusable stopped before frame 63"
# Usable, but flagged: used, the flags on the c line.
sed -e 's/"usable": false, "unusable_because": \[[^]]*\]/"usable": true/' -e 's/"c": 0.03/"c": 3.1/' "$work/unusable.json" >"$work/flagged.json"
"$example" "$work/flagged.json" >"$work/flagged.out" || fail "engine_integration with a usable, flagged entry"
head -1 "$work/flagged.out" | grep -q "^c = 3.10 texels (.*); flags: one_participant$" ||
  fail "engine_integration does not print the entry's flags: $(head -1 "$work/flagged.out")"
# The published entry states no kernel (the study's disk) and the example filters with the grid: a
# fallback, said with what would match, and nothing else (no flags, not NOT USABLE).
head -1 "$work/example.txt" |
  grep -q "^c = 3.47 texels (pcf entry (published, 10 participants), not measured for pcf grid: [^;]*; a pcf grid entry would match)$" ||
  fail "the published entry's line is not the kernel fallback alone: $(head -1 "$work/example.txt")"
status=0
"$example" --allow-unusabel "$work/flagged.json" >/dev/null 2>&1 || status=$?
((status == 2)) || fail "engine_integration with an unknown option exited $status, not 2"

step "pkg-config penumbra-adaptive"
pc=$(find "$prefix" -name penumbra-adaptive.pc)
[[ -n $pc ]] || fail "no penumbra-adaptive.pc under $prefix"
export PKG_CONFIG_LIBDIR=${pc%/*} PKG_CONFIG_PATH=
flags=$(pkg-config --cflags --libs penumbra-adaptive)
echo "pkg-config --cflags --libs penumbra-adaptive: $flags"
for f in $(pkg-config --libs --static penumbra-adaptive); do
  [[ $f == -L* || $f == -lpenumbra_* ]] || fail "penumbra-adaptive.pc links $f"
done
# shellcheck disable=SC2086  # the flags are words
"$cxx" -std=c++17 -Wall -Wextra -Wpedantic -Werror "$source/tests/install/consumer/size_shadow_map.cpp" $flags -o "$work/pc_size_shadow_map"
"$work/pc_size_shadow_map" "$prefix/share/penumbra/calibration/default.json"
# shellcheck disable=SC2086
"$cxx" -std=c++17 -Wall -Wextra -Wpedantic -Werror "$source/examples/engine_integration/main.cpp" $flags -o "$work/pc_engine_integration"
"$work/pc_engine_integration" "$prefix/share/penumbra/calibration/default.json" | cmp - "$work/example.txt" || fail "the example built with pkg-config printed something else"

step "installed tools: --version, --help, the installed data"
tools=(penumbra-render penumbra-scene penumbra-bench penumbra-demo penumbra-quest penumbra-observer-curve penumbra-observer-fit
       penumbra-study penumbra-fit penumbra-compare)
[[ -x $prefix/bin/penumbra-view || ! -e $build/renderer/penumbra-view ]] || fail "penumbra-view built but not installed"
[[ -x $prefix/bin/penumbra-view ]] && tools+=(penumbra-view)
for tool in "${tools[@]}"; do
  line=$("$prefix/bin/$tool" --version)
  [[ $line =~ ^$tool\ ${version//./\\.}\ \(git\ ([0-9a-f]{7}(-dirty)?|unknown)\)$ ]] || fail "$tool --version: '$line'"
  help=$("$prefix/bin/$tool" --help)  # (not piped into grep -q, which would leave the tool writing into a closed pipe)
  page=$(sed -n 's/^Documentation: //p' <<<"$help")
  [[ $page == "$prefix/share/doc/penumbra/"*.md && -f $page ]] || fail "$tool --help names the docs page '$page'"
  grep -q "^Exit codes: .*$prefix/share/doc/penumbra/tools.md$" <<<"$help" || fail "$tool --help: no exit codes"
done
echo "${#tools[@]} tools: $("$prefix/bin/penumbra-render" --version)"
help=$("$prefix/bin/penumbra-demo" --help)
grep -q -- "--calibration TEXT:PATH=$prefix/share/penumbra/calibration/default.json$" <<<"$help" ||
  fail "penumbra-demo's default calibration is not the installed one"
"$prefix/bin/penumbra-study" display-check --config default >"$work/display-check.txt" || fail "penumbra-study display-check --config default"
help=$("$prefix/bin/penumbra-study" run --help)
grep -q "shipped in $prefix/share/penumbra/studies: .*default" <<<"$help" ||
  fail "penumbra-study run --help does not list the installed study configs"
# The prefix is kept only when a check failed.
rm -rf "$prefix"
step "done"
