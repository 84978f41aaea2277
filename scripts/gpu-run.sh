#!/bin/sh
# The GPU bundle's launcher (copied to BUNDLE/run by scripts/gpu-bundle.sh; docs/gpu.md):
#   BUNDLE/run PROGRAM [ARGS...]   runs PROGRAM from the payload's bin/ or tests/
#   BUNDLE/run --root              prints the unpacked payload's folder
#   BUNDLE/run --print-env         prints the EGL variables it sets
# The payload (BUNDLE/payload.tar.xz: bin/, tests/, lib/) is unpacked once, outside the carried
# folder, into ${PENUMBRA_BUNDLE_CACHE:-${TMPDIR:-/tmp}}/penumbra-gpu-bundle-<checksum>/. Its
# programs find lib/ through their $ORIGIN/../lib rpath (DT_RPATH, which also serves the
# libraries' own dependencies), so no library path is set for the bundle.
# What it sets is for EGL where the NVIDIA driver keeps its files apart (/usr/local/nvidia on the
# device machine): the vendor file __EGL_VENDOR_LIBRARY_FILENAMES, unless the system's vendor
# folders name NVIDIA or the variable is set, and the driver's library folder when the loader
# cache lacks libEGL_nvidia.so.0.
here=$(cd "$(dirname "$0")" && pwd)
PATH=${PATH:-/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin}
export PATH

sum=$(cut -c1-16 "$here/payload.sha256" 2>/dev/null)
if [ -z "$sum" ] || [ ! -f "$here/payload.tar.xz" ]; then
  echo "run: $here has no payload.tar.xz/payload.sha256 (make the bundle with scripts/gpu-bundle.sh)" >&2
  exit 2
fi
cache=${PENUMBRA_BUNDLE_CACHE:-${TMPDIR:-/tmp}}
root=$cache/penumbra-gpu-bundle-$sum
if [ ! -d "$root" ]; then
  tmp=$(mktemp -d "$cache/.penumbra-gpu-bundle.XXXXXX") || exit 1
  if command -v xz >/dev/null 2>&1; then
    xz -dc "$here/payload.tar.xz" | tar -C "$tmp" -xf -
  else
    python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' "$here/payload.tar.xz" "$tmp"
  fi
  if [ ! -d "$tmp/lib" ] || [ ! -d "$tmp/bin" ]; then
    rm -rf "$tmp"
    echo "run: cannot unpack $here/payload.tar.xz into $cache" >&2
    exit 1
  fi
  chmod 755 "$tmp"
  mv -T "$tmp" "$root" 2>/dev/null || rm -rf "$tmp"  # a run beside this one unpacked it first
fi

nv=/usr/local/nvidia
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}${__EGL_VENDOR_LIBRARY_DIRS:-}" ] &&
   [ -f "$nv/share/glvnd/egl_vendor.d/10_nvidia.json" ] &&
   ! ls /usr/share/glvnd/egl_vendor.d/*nvidia* /etc/glvnd/egl_vendor.d/*nvidia* >/dev/null 2>&1; then
  __EGL_VENDOR_LIBRARY_FILENAMES=$nv/share/glvnd/egl_vendor.d/10_nvidia.json
  export __EGL_VENDOR_LIBRARY_FILENAMES
fi
for d in "$nv/lib64" "$nv/lib"; do
  if [ -e "$d/libEGL_nvidia.so.0" ] && ! ldconfig -p 2>/dev/null | grep -q 'libEGL_nvidia\.so\.0 '; then
    LD_LIBRARY_PATH=$d${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export LD_LIBRARY_PATH
    break
  fi
done

case "${1:-}" in
  --root) echo "$root"; exit 0 ;;
  --print-env)
    echo "__EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-}"
    echo "__EGL_VENDOR_LIBRARY_DIRS=${__EGL_VENDOR_LIBRARY_DIRS:-}"
    echo "LD_LIBRARY_PATH=${LD_LIBRARY_PATH:-}"
    exit 0 ;;
  "") echo "usage: $0 PROGRAM [ARGS...] | --root | --print-env (PROGRAM from $root/bin or tests)" >&2; exit 2 ;;
esac
prog=$1
shift
for d in bin tests; do
  if [ -x "$root/$d/$prog" ]; then exec "$root/$d/$prog" "$@"; fi
done
echo "run: no program '$prog' in $root/bin or $root/tests" >&2
exit 127
