#!/usr/bin/env bash
# Installs Penumbra's build and run dependencies from Debian packages, only those missing.
# Idempotent: a second run installs nothing and prints one line.
# --test adds what only the tests need (the test command, scripts/run-tests.sh, passes it).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"

packages=(
  cmake g++ make pkg-config
  dpkg-dev  # cpack -G DEB: dpkg-shlibdeps writes the package's Depends (tests/install/deb_test.sh)
  libgtest-dev libgmock-dev libbenchmark-dev
  libepoxy-dev libegl-dev libegl1-mesa-dev libgl1-mesa-dri libglm-dev
  libglfw3-dev libimgui-dev libstb-dev
  libopencv-dev libopencv-contrib-dev
  libceres-dev
  libopenimageio-dev openimageio-tools
  libpng-dev libopenexr-dev  # the minimal image backend of the gpu-bundle preset (docs/gpu.md)
  libassimp-dev libcli11-dev nlohmann-json3-dev
  libembree-dev  # the ray-traced area-light reference (renderer/metrics/ray_traced.h)
  python3-matplotlib
  xvfb xauth fonts-dejavu-core
  xdotool  # the study GUI test types keys and clicks into the participant window under Xvfb
  parallel  # GNU parallel: scripts/predict-calibration.sh --jobs runs the shards on local slots or lab machines (docs/cluster.md)
  clang libclang-rt-14-dev  # the fuzz preset: clang's libFuzzer and sanitizer runtimes (Debian 12: clang 14)
  libcpp-httplib-dev nodejs  # penumbra-study serve and its page (web/, docs/study-online.md)
)
command -v npm >/dev/null || packages+=(npm)  # Debian's npm, unless node came with its own
if [[ "${1:-}" == "--test" ]]; then
  packages+=(chromium)  # the online study's real-browser test (puppeteer-core drives it)
  # A single-node Slurm that study.predict_calibration_slurm_array starts and stops itself (docs/cluster.md)
  packages+=(munge slurmctld slurmd slurm-client)
fi

# The online study's page: jsPsych from npm as web/package-lock.json pins it (the build copies it
# into the page's static files; no CDN at run time). Installed again only when the lock file is
# newer than the install; nothing downloads a browser.
web_setup() {
  if [[ -f "$root/web/node_modules/.package-lock.json" && "$root/web/node_modules/.package-lock.json" -nt "$root/web/package-lock.json" ]]; then
    return 0
  fi
  (cd "$root/web" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --ignore-scripts >/dev/null)
  echo "setup: web/: npm ci"
}

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  web_setup
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

if [[ $(id -u) -ne 0 ]]; then
  echo "setup: missing packages (${missing[*]}); run this script as root (sudo $0) to install them" >&2
  exit 1
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
web_setup
echo "setup: done"
