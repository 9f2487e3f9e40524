#!/usr/bin/env bash
# mesolab main job. Installs missing Debian packages, builds, then opens the GUI when a display
# is available; otherwise runs the headless showcase (a few minutes on 2 cores once built): the GL
# context, a capture of every preset in presets/ into build/showcase/, a figure made through the
# Python module (examples/heidrich_fig1.py) and three short timing tables.
# The clone's tracked files stay as they are (the gallery in screenshots/ is refreshed on purpose,
# with `build/mesolab capture presets -o screenshots`).
# The full timing tables live in the technique pages (core/*/README.md); regenerate them with
# `build/mesolab bench --update-pages`. Arguments go to `mesolab gui` (e.g. a preset).
# MESOLAB_HEADLESS=1 runs the showcase even when a display is available.
set -euo pipefail
cd "$(dirname "$0")"
source .ci/setup.sh
ensure_packages
build build
# Large stage results (look-up tables, visibility, light images) on transparent huge pages:
# fresh allocations of tens of MB cost several times less where page faults are slow.
export GLIBC_TUNABLES="${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1"

if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${MESOLAB_HEADLESS:-}" ]; then
  exec ./build/mesolab gui "$@"
fi
echo "== no display: headless showcase"
./build/mesolab info
./build/mesolab capture presets -o build/showcase
echo "== captures (PNG and a JSON sidecar each): build/showcase/"
if [ -e build/python ] && ls build/python/mesolab/_mesolab*.so >/dev/null 2>&1; then
  echo "== Python (import mesolab): Heidrich et al. 2000, Fig. 1 as a matplotlib figure"
  PYTHONPATH=build/python PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg /usr/bin/python3 examples/heidrich_fig1.py build/showcase
fi
echo "== short bench: three fast tables, median of 3 runs per cell"
./build/mesolab bench basic microgeom-geometry bumpsynth-frame --repeat 3
echo "== full timing tables: core/basic/README.md, core/microgeom/README.md, core/bumpsynth/README.md, core/translucency/README.md, core/cloth/README.md"
echo "   regenerate them (every table, median of 5 runs; about 18 minutes on an idle 2-core machine):"
echo "     GLIBC_TUNABLES=glibc.malloc.hugetlb=1 build/mesolab bench --update-pages"
