#!/usr/bin/env bash
# Throwaway virtualenv with SurfaceTopography, the peer of `asperity surface stats` in
# benches/surface.rs. SurfaceTopography is never a dependency of asperity.
# Usage: benches/peers/setup_surfacetopography.sh [VENV_DIR]
#        (default /tmp/asperity-surface-peers-venv)
set -euo pipefail
VENV="${1:-/tmp/asperity-surface-peers-venv}"
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet --only-binary=:all: SurfaceTopography numpy
"$VENV/bin/python" -c "import SurfaceTopography, numpy; print('SurfaceTopography', SurfaceTopography.__version__, 'numpy', numpy.__version__)"
