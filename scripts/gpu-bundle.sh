#!/usr/bin/env bash
# Gathers what the GPU check runs into one folder that the device tool carries (docs/gpu.md):
# builds the gpu-bundle preset (build-gpu-bundle/: headless, image files through libpng +
# OpenEXR instead of OpenImageIO, $ORIGIN/../lib rpath), then writes .gpu-bundle/ (git-ignored):
#   payload.tar.xz  bin/    penumbra-render, penumbra-bench, penumbra-demo (stripped)
#                   tests/  the test binaries that hold `ctest -L gl` tests (stripped)
#                   lib/    every shared library they load except glibc's and libglvnd's (ldd)
#                   (about 60 MiB unpacked, over the carry limit: `run` unpacks it once into
#                   ${TMPDIR:-/tmp}/penumbra-gpu-bundle-<checksum>/, outside the carried folder)
#   gl-tests.txt    each test binary with its gl tests as a GoogleTest filter
#   libraries.txt   each bundled library and the file it was copied from
#   gl-debs/        libglvnd's Debian packages (libEGL, libGLX, libOpenGL, ...) for a machine
#                   without them (the device machine: gpu-check.sh unpacks them into /)
#   data/           calibration/default.json (penumbra-demo --calibration)
#   run, gpu-check.sh, gpu-gl-tests.sh, gpu_summary.py, gpu_cost_model.py, VERSION
# The folder is replaced only when the whole bundle is made; this script refuses more than
# 48 MiB (the device tool carries 64 MiB, the working tree included).
#   --out DIR      the bundle folder (default .gpu-bundle)
#   --jobs N       build jobs (default: the number of cores)
#   --no-build     bundle build-gpu-bundle/ as it is
#   --no-gl-debs   leave out gl-debs/ (no package download; the device then needs the .gl of
#                  the device tool's README)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out=.gpu-bundle
jobs=$(nproc)
build=1
gl_debs=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out=${2:?--out needs a folder}; shift ;;
    --jobs) jobs=${2:?--jobs needs a number}; shift ;;
    --no-build) build=0 ;;
    --no-gl-debs) gl_debs=0 ;;
    -h|--help) sed -n '2,27p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu-bundle: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
build_dir=build-gpu-bundle
max_bytes=$((48 * 1024 * 1024))
apps=(penumbra-render penumbra-bench penumbra-demo)
# glibc (the base system) and libglvnd (the GL loader, with the EGL vendor files and the driver):
# taken from the machine the bundle runs on, never bundled.
system_libs='^(linux-vdso\.so|ld-linux-x86-64\.so|libc\.so|libm\.so|libmvec\.so|libdl\.so|libpthread\.so|librt\.so|libresolv\.so|libutil\.so|libanl\.so|libnsl\.so|libEGL\.so|libGLdispatch\.so|libGLX\.so|libOpenGL\.so|libGL\.so|libGLESv1_CM\.so|libGLESv2\.so)'
# Mesa and NVIDIA vendor libraries must never shadow the machine's driver.
driver_libs='^(libEGL_|libGLX_|libgallium|libglapi|libgbm|libnvidia|libcuda|.*_dri\.so)'

if [[ $build -eq 1 ]]; then
  launchers=()
  if command -v ccache >/dev/null; then
    launchers=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  cmake --preset gpu-bundle "${launchers[@]}" >/dev/null
  cmake --build --preset gpu-bundle -j "$jobs"
fi
[[ -f $build_dir/CTestTestfile.cmake ]] || { echo "gpu-bundle: no $build_dir/ (run without --no-build)" >&2; exit 1; }

stage=$(mktemp -d "$root/.gpu-bundle.new.XXXXXX")  # the folder being made (ignored: /.gpu-bundle*/)
payload=$(mktemp -d)                                # bin/ tests/ lib/ before they are packed
check=$(mktemp -d)                                  # the packed payload, unpacked again and checked
trap 'rm -rf "$stage" "$payload" "$check"' EXIT
mkdir -p "$payload/bin" "$payload/tests" "$payload/lib" "$stage/data/calibration"

# The gl tests: binary, test count, filter (ctest's own list, so a new gl test is bundled too).
ctest --test-dir "$build_dir" -L gl --show-only=json-v1 >"$stage/ctest-gl.json"
python3 - "$stage/ctest-gl.json" "$root/$build_dir" >"$stage/gl-tests.in" <<'PY'
import json, os, sys
tests = json.load(open(sys.argv[1]))["tests"]
build = os.path.realpath(sys.argv[2])
by_binary = {}
for t in tests:
    props = {p["name"]: p["value"] for p in t.get("properties", [])}
    if props.get("DISABLED"):
        continue
    cmd = t.get("command") or []
    filters = [a[len("--gtest_filter="):] for a in cmd if a.startswith("--gtest_filter=")]
    if not cmd or not filters or not os.path.realpath(cmd[0]).startswith(build + "/"):
        sys.exit(f"gpu-bundle: gl test {t['name']} is not a GoogleTest binary of {build}: {cmd}")
    by_binary.setdefault(cmd[0], []).extend(filters)
if not by_binary:
    sys.exit("gpu-bundle: ctest -L gl lists no tests (is the build complete?)")
for exe, names in sorted(by_binary.items(), key=lambda kv: -len(kv[1])):
    print(f"{exe}\t{len(names)}\t{':'.join(names)}")
PY

# Executables: the apps and the gl test binaries, stripped.
exes=()
for a in "${apps[@]}"; do
  exes+=("$build_dir/renderer/$a")
  install -m 755 "$build_dir/renderer/$a" "$payload/bin/$a"
done
printf '# binary\ttests\tgtest filter: the tests `ctest -L gl` runs (scripts/gpu-bundle.sh)\n' >"$stage/gl-tests.txt"
while IFS=$'\t' read -r exe count filter; do
  exes+=("$exe")
  install -m 755 "$exe" "$payload/tests/${exe##*/}"
  printf '%s\t%s\t%s\n' "${exe##*/}" "$count" "$filter" >>"$stage/gl-tests.txt"
done <"$stage/gl-tests.in"
rm "$stage/gl-tests.in" "$stage/ctest-gl.json"
strip --strip-all "$payload"/bin/* "$payload"/tests/*

# Their shared libraries, as the loader finds them here, except the system's.
declare -A libs=()
for exe in "${exes[@]}"; do
  while read -r name arrow path _; do
    [[ "$arrow" == "=>" ]] || continue
    [[ "$name" =~ $system_libs ]] && continue
    if [[ "$path" == "not" ]]; then echo "gpu-bundle: $exe: $name not found" >&2; exit 1; fi
    if [[ "$name" =~ $driver_libs ]]; then echo "gpu-bundle: $exe links $name, a driver library; refusing to bundle it" >&2; exit 1; fi
    libs[$name]=$path
  done < <(ldd "$exe")
done
for name in $(printf '%s\n' "${!libs[@]}" | sort); do
  cp -L "${libs[$name]}" "$payload/lib/$name"
  chmod 644 "$payload/lib/$name"
  printf '%s\t%s\n' "$name" "$(readlink -f "${libs[$name]}")"
done >"$stage/libraries.txt"
strip --strip-unneeded "$payload"/lib/*
unpacked_bytes=$(du -sb "$payload" | cut -f1)

tar -C "$payload" --owner=0 --group=0 --numeric-owner --mtime=@0 --sort=name -cf - bin tests lib | xz -6 -T1 >"$stage/payload.tar.xz"
sha256sum "$stage/payload.tar.xz" | cut -c1-64 >"$stage/payload.sha256"

# Check, on the payload unpacked as `run` unpacks it: every library of every program resolves
# into it, or is the system's (glibc, libglvnd).
tar -C "$check" -xJf "$stage/payload.tar.xz"
for f in "$check"/bin/* "$check"/tests/*; do
  while read -r name arrow path _; do
    [[ "$arrow" == "=>" ]] || continue
    [[ "$name" =~ $system_libs ]] && continue
    if [[ "$path" != "$check/"* ]]; then
      echo "gpu-bundle: ${f#"$check"/}: $name resolves to $path, not into the bundle" >&2
      exit 1
    fi
  done < <(ldd "$f")
done

cp data/calibration/default.json "$stage/data/calibration/"
install -m 755 scripts/gpu-run.sh "$stage/run"
install -m 755 scripts/gpu-check.sh scripts/gpu-gl-tests.sh "$stage/"
install -m 644 scripts/gpu_summary.py "$stage/"
install -m 644 scripts/gpu_cost_model.py "$stage/"

if [[ $gl_debs -eq 1 ]]; then
  mkdir -p "$stage/gl-debs"
  packages=(libegl1 libglvnd0 libglx0 libopengl0 libgl1)
  if [[ $(ls "$out"/gl-debs/*.deb 2>/dev/null | wc -l) -eq ${#packages[@]} ]]; then
    cp "$out"/gl-debs/*.deb "$stage/gl-debs/"
  else
    # As the device tool's README fetches them: amd64, from this machine's Debian sources.
    lists=$(mktemp -d)
    mkdir -p "$lists/partial"
    o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$lists")
    apt-get "${o[@]}" update -qq 2>&1 | grep -v 'unsandboxed' || true
    (cd "$stage/gl-debs" && apt-get "${o[@]}" download -qq "${packages[@]}" 2>&1 | grep -v 'unsandboxed' || true)
    rm -rf "$lists"
    [[ $(ls "$stage"/gl-debs/*.deb 2>/dev/null | wc -l) -eq ${#packages[@]} ]] ||
      { echo "gpu-bundle: could not download ${packages[*]} (use --no-gl-debs)" >&2; exit 1; }
  fi
fi

{
  echo "commit: $(git describe --always --dirty 2>/dev/null || echo unknown)"
  echo "made: $(date -u +%FT%TZ) on $(uname -srm), $(ldd --version | head -1)"
  echo "payload: $(cut -c1-12 "$stage/payload.sha256"), $((unpacked_bytes / 1024 / 1024)) MiB unpacked (preset gpu-bundle, $build_dir/)"
} >"$stage/VERSION"

bytes=$(du -sb "$stage" | cut -f1)
if ((bytes > max_bytes)); then
  echo "gpu-bundle: the bundle is $((bytes / 1024 / 1024)) MiB, over the $((max_bytes / 1024 / 1024)) MiB this script allows (the device tool carries 64 MiB)" >&2
  exit 1
fi
chmod 755 "$stage"
rm -rf "${out:?}.old"
if [[ -e "$out" ]]; then mv "$out" "$out.old"; fi
mv "$stage" "$out"
rm -rf "${out:?}.old"
mib() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1048576 }'; }
echo "gpu-bundle: $out/: $(mib "$bytes") MiB to carry; payload $(mib "$unpacked_bytes") MiB unpacked:" \
  "${#apps[@]} programs, $(($(wc -l <"$out/gl-tests.txt") - 1)) test binaries, ${#libs[@]} libraries"
