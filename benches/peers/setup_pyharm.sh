#!/usr/bin/env bash
# Throwaway virtualenv with pyHarm (Safran's harmonic-balance code, PyPI package pyharm-os), the
# peer of benches/response.rs. Never a dependency of asperity.
# Usage: benches/peers/setup_pyharm.sh [VENV_DIR]   (default /tmp/asperity-pyharm-venv)
set -euo pipefail
VENV="${1:-/tmp/asperity-pyharm-venv}"
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet "pyharm-os==1.2.2"
"$VENV/bin/python" -c "import pyHarm; print('pyHarm', pyHarm.__version__ if hasattr(pyHarm, '__version__') else '1.2.2')"
