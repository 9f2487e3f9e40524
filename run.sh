#!/usr/bin/env bash
# mesolab main job. Installs missing Debian packages, builds, then opens the GUI when a display
# is available; otherwise runs the headless showcase: captures every preset in presets/ into
# screenshots/ and prints the timing tables. Arguments go to `mesolab gui` (e.g. a preset).
set -euo pipefail
cd "$(dirname "$0")"
source .ci/setup.sh
ensure_packages
build build

if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${MESOLAB_HEADLESS:-}" ]; then
  exec ./build/mesolab gui "$@"
fi
echo "== no display: headless showcase"
./build/mesolab info
./build/mesolab capture presets -o screenshots
./build/mesolab bench --repeat 5
