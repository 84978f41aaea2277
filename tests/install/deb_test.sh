#!/usr/bin/env bash
# ctest -L install: install.deb (tests/install/CMakeLists.txt). The Debian package as a user gets it:
#   1. cpack -G DEB builds it (stripped, Depends from dpkg-shlibdeps);
#   2. its Depends name the shared libraries the tools link; dpkg-deb -c lists the tools, the
#      headers (under /usr/include/penumbra/ and nowhere else in /usr/include), the CMake and
#      pkg-config files, the data and the docs;
#   3. unpacked into a scratch root (dpkg -x, no installation), the tools run from there and use the
#      data unpacked beside them: penumbra-render's default calibration, penumbra-study's shipped
#      study configs;
#   4. examples/engine_integration builds against the unpacked root (the CMake package is
#      relocatable) and runs.
# usage: deb_test.sh BUILD_DIR SOURCE_DIR WORK_DIR VERSION
set -euo pipefail
build=$1 source=$2 work=$3 version=$4
rm -rf "$work"
mkdir -p "$work"
start=$SECONDS
step() { echo "== [$((SECONDS - start)) s] $*"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

step "cpack -G DEB"
cpack --config "$build/CPackConfig.cmake" -G DEB -B "$work/cpack" >"$work/cpack.log" 2>&1 || { cat "$work/cpack.log"; fail "cpack"; }
deb=$work/cpack/penumbra_${version}_$(dpkg --print-architecture).deb
[[ -f $deb ]] || fail "no $deb ($(ls "$work/cpack"))"
echo "$(basename "$deb"): $(du -k "$deb" | cut -f1) KiB"

step "dpkg-deb -I, -c"
depends=$(dpkg-deb -f "$deb" Depends)
echo "Depends: $depends"
for lib in libc6 libstdc++6 libepoxy0 libegl1 libassimp; do
  [[ $depends == *"$lib"* ]] || fail "Depends does not name $lib"
done
dpkg-deb -c "$deb" | awk '{print $6}' >"$work/contents.txt"
for f in ./usr/bin/penumbra-render ./usr/bin/penumbra-study ./usr/bin/penumbra-fit ./usr/bin/penumbra-quest \
         ./usr/include/penumbra/adaptive/resolution_rule.h ./usr/include/penumbra/quest/quest.h ./usr/include/penumbra/log/trial_log.h \
         ./usr/include/penumbra/shadows/renderer.h ./usr/lib/libpenumbra_adaptive.a ./usr/lib/cmake/Penumbra/PenumbraConfig.cmake \
         ./usr/lib/cmake/Penumbra/PenumbraConfigVersion.cmake ./usr/lib/cmake/Penumbra/PenumbraAdaptiveTargets.cmake \
         ./usr/lib/pkgconfig/penumbra-adaptive.pc ./usr/share/penumbra/calibration/default.json \
         ./usr/share/penumbra/studies/default.json ./usr/share/penumbra/scripts/plot_fit.py ./usr/share/doc/penumbra/tools.md \
         ./usr/share/doc/penumbra/examples/engine_integration/main.cpp; do
  grep -qx -- "$f" "$work/contents.txt" || fail "the package has no $f"
done
others=$(grep '^\./usr/include/.' "$work/contents.txt" | grep -v '^\./usr/include/penumbra/' || true)
[[ -z $others ]] || fail "the package puts more than penumbra/ into /usr/include: $others"
awk -F/ 'NF > 2 && $NF != "" {print "  " $2 "/" $3 "/" $4}' "$work/contents.txt" | sort | uniq -c

step "dpkg -x into $work/root: the tools and the data unpacked beside them"
dpkg -x "$deb" "$work/root"
usr=$work/root/usr
line=$("$usr/bin/penumbra-render" --version)
[[ $line =~ ^penumbra-render\ ${version//./\\.}\ \(git\ ([0-9a-f]{7}(-dirty)?|unknown)\)$ ]] || fail "penumbra-render --version: '$line'"
echo "$line"
"$usr/bin/penumbra-render" --scene demo --technique pcf --resolution 256 --width 64 --height 36 --frames 1 --warmup 0 \
  -o "$work/render" >"$work/render.log" 2>&1 || { cat "$work/render.log"; fail "penumbra-render from the unpacked package"; }
calibration=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["calibration"]["file"])' "$work/render/report.json")
[[ $calibration == "$usr/share/penumbra/calibration/default.json" ]] || fail "penumbra-render used the calibration $calibration"
echo "penumbra-render: calibration $calibration"
"$usr/bin/penumbra-study" display-check --config default-yesno >"$work/display-check.txt" ||
  fail "penumbra-study display-check --config default-yesno from the unpacked package"
help=$("$usr/bin/penumbra-fit" --help)
grep -q "^Documentation: $usr/share/doc/penumbra/fit.md$" <<<"$help" || fail "penumbra-fit --help does not name the unpacked docs"
echo "penumbra-study display-check --config default-yesno: $(head -1 "$work/display-check.txt")"

step "examples/engine_integration against the unpacked root"
cmake -S "$source/examples/engine_integration" -B "$work/example" -DCMAKE_PREFIX_PATH="$usr" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  >"$work/example-configure.log" || { cat "$work/example-configure.log"; fail "configure"; }
cmake --build "$work/example" -j 1 >"$work/example-build.log" || { cat "$work/example-build.log"; fail "build"; }
"$work/example/engine_integration" "$usr/share/penumbra/calibration/default.json" >"$work/example.txt"
head -n 2 "$work/example.txt"
# The package stays; the staging tree and the unpacked root are kept only when a check failed.
rm -rf "$work/cpack/_CPack_Packages" "$work/root"
step "done"
