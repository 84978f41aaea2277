#!/usr/bin/env bash
# Runs the GPU bundle in a clean room (docs/gpu.md): a chroot that holds glibc, libglvnd, Mesa's
# EGL vendor with its llvmpipe driver and their own dependencies, and the few tools the bundle's
# scripts call, but none of the libraries that Penumbra's Debian -dev packages bring (OpenCV,
# Assimp, epoxy, OpenEXR, libpng, TBB, LAPACK, ...). Copies the bundle in, then, with `env -i`,
# prints `ld.so --list` of every program and runs penumbra-render, a short penumbra-demo and
# penumbra-bench, and (with --gl-tests) every gl test through gpu-gl-tests.sh.
# Needs root (chroot, mknod, mount -t proc: glibc finds $ORIGIN through /proc/self/exe).
#   --bundle DIR   the bundle (default .gpu-bundle)
#   --root DIR     the clean room, made afresh (default /tmp/penumbra-cleanroom)
#   --gl-tests     also run every gl test (llvmpipe: several minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=.gpu-bundle
room=/tmp/penumbra-cleanroom
gl_tests=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bundle) bundle=${2:?--bundle needs a folder}; shift ;;
    --root) room=${2:?--root needs a folder}; shift ;;
    --gl-tests) gl_tests=1 ;;
    -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu-bundle-cleanroom: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
[[ -f "$bundle/payload.tar.xz" ]] || { echo "gpu-bundle-cleanroom: $bundle is not a bundle (scripts/gpu-bundle.sh)" >&2; exit 2; }
[[ $(id -u) -eq 0 ]] || { echo "gpu-bundle-cleanroom: needs root (chroot, mount)" >&2; exit 2; }
room=$(realpath -m "$room")
case "$room" in /tmp/?*) ;; *) echo "gpu-bundle-cleanroom: --root must lie under /tmp, not $room" >&2; exit 2 ;; esac
if mountpoint -q "$room/proc" 2>/dev/null; then umount "$room/proc"; fi
rm -rf --one-file-system "$room"
mkdir -p "$room"
trap 'if mountpoint -q "$room/proc"; then umount "$room/proc"; fi' EXIT

copy() {  # a file, symlinks resolved, to the same path in the room
  [[ -e "$1" ]] || return 0
  mkdir -p "$room$(dirname "$1")"
  cp -L "$1" "$room$1"
}
with_deps() {  # a program or library and everything ldd says it loads
  copy "$1"
  local d
  for d in $(ldd "$1" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }'); do copy "$d"; done
}
mkdir -p "$room/usr/bin" "$room/usr/sbin" "$room/usr/lib/x86_64-linux-gnu" "$room/usr/lib64" "$room/dev" "$room/proc" "$room/tmp"
chmod 1777 "$room/tmp"
for l in bin lib lib64 sbin; do ln -s "usr/$l" "$room/$l"; done
multiarch=/usr/lib/x86_64-linux-gnu
copy /usr/lib64/ld-linux-x86-64.so.2
for l in $(dpkg -L libc6 | grep -E '^(/usr)?/lib/x86_64-linux-gnu/lib[^/]*\.so[.0-9]*$'); do copy "$l"; done  # glibc
for l in libEGL.so.1 libGLdispatch.so.0 libGLX.so.0 libOpenGL.so.0 libGL.so.1; do with_deps "$multiarch/$l"; done  # libglvnd
with_deps "$multiarch/libEGL_mesa.so.0"  # the EGL vendor and its software driver
with_deps "$multiarch/dri/swrast_dri.so"
copy /usr/share/glvnd/egl_vendor.d/50_mesa.json
for t in bash dash dirname cut mktemp chmod mv rm ls cat mkdir wc nproc tar xz grep env; do with_deps "/usr/bin/$t"; done
with_deps /usr/sbin/ldconfig
ln -s dash "$room/usr/bin/sh"
mknod -m 666 "$room/dev/null" c 1 3
mknod -m 666 "$room/dev/zero" c 1 5
mknod -m 666 "$room/dev/urandom" c 1 9
cp -r "$bundle" "$room/bundle"
mount -t proc proc "$room/proc"

forbidden='libopencv|libassimp|libepoxy|libOpenEXR|libpng|libtbb|liblapack|libblas|libgfortran|libdraco|libOpenImageIO|libceres'
echo "clean room: $room ($(du -sh --exclude=proc "$room" | cut -f1)); libraries of Penumbra's -dev packages in it:" \
  "$(find "$room/usr/lib" -name 'lib*.so*' | grep -cE "$forbidden" || true)"
in_room() { env -i /usr/sbin/chroot "$room" "$@"; }
payload=$(in_room /bundle/run --root)
echo "== ld.so --list: where each program's libraries come from (bundle = $payload/lib)"
for f in $(cd "$room$payload" && ls bin/* tests/*); do
  in_room /lib64/ld-linux-x86-64.so.2 --list "$payload/$f" |
    awk -v b="$payload" -v f="$f" '$2 == "=>" { n++; if (index($3, b) == 1) inb++; else sys = sys " " $1 } END { printf "  %-26s %2d libraries: %2d in the bundle, system:%s\n", f, n, inb, sys }'
done
echo "== penumbra-render --technique pcss --resolution 1024"
cal=/bundle/data/calibration/default.json  # the apps' default is a path into the source tree
in_room /bundle/run penumbra-render --calibration $cal --technique pcss --resolution 1024 -o /tmp/render | tail -2
echo "== penumbra-demo --headless --frames 2"
in_room /bundle/run penumbra-demo --headless --no-plot --frames 2 --calibration $cal -o /tmp/demo 2>/dev/null | tail -4
echo "== penumbra-bench (demo scene; hard, pcf, pcss; 256, 1024)"
in_room /bundle/run penumbra-bench --calibration $cal --scenes demo --techniques hard,pcf,pcss --resolutions 256,1024 --width 160 --height 90 --frames 2 \
  --area-samples 4 --no-plot -o /tmp/bench 2>/dev/null | tail -1
if [[ $gl_tests -eq 1 ]]; then
  echo "== gpu-gl-tests.sh (every ctest -L gl test)"
  in_room /usr/bin/env JOBS="${JOBS:-1}" /bundle/gpu-gl-tests.sh /tmp/gl-tests
fi
echo "clean room: every run above passed"
