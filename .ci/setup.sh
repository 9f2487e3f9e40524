# Shared by run.sh, test.sh and .ci/run (sourced): install missing Debian 12 packages, build.
# Safe to rerun: installs only what is missing, builds incrementally.

MESOLAB_PACKAGES=(
  build-essential cmake pkg-config git
  libglfw3-dev libimgui-dev libglm-dev libepoxy-dev libegl-dev libgl-dev
  libegl-mesa0 libgl1-mesa-dri libglx-mesa0
  libopenmesh-dev libopenimageio-dev libeigen3-dev nlohmann-json3-dev libcli11-dev libtbb-dev
  libceres-dev libembree-dev libimath-dev libzip-dev
  libfreetype-dev fonts-dejavu-core
  libgtest-dev libgmock-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-openimageio python3-distributed
  xvfb xauth
  ccache
)

ensure_packages() {
  local missing=()
  for p in "${MESOLAB_PACKAGES[@]}"; do
    if [ "$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null)" != "installed" ]; then missing+=("$p"); fi
  done
  if [ ${#missing[@]} -eq 0 ]; then return 0; fi
  echo "== installing Debian packages: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# build DIR [cmake args...]
build() {
  local dir="$1"; shift
  local jobs
  jobs="$(nproc 2>/dev/null || echo 2)"
  echo "== building $dir"
  # ccache (installed with the packages above) makes rebuilds of a fresh clone cheap: paths under
  # the clone are taken as relative to it, and the folder is not hashed (debug builds), so another
  # clone of the same commit compiles from the cache. The build does not need it.
  local launcher=()
  if command -v ccache >/dev/null 2>&1; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
    export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  fi
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}
