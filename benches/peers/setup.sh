#!/usr/bin/env bash
# Create a throwaway virtualenv with the peer codes used by benches/peers/*.py.
# tamaas is never a dependency of asperity: it lives only in this venv.
# Usage: benches/peers/setup.sh [VENV_DIR]   (default /tmp/asperity-peers-venv)
set -euo pipefail
VENV="${1:-/tmp/asperity-peers-venv}"
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet "tamaas==2.9.0" numpy
"$VENV/bin/python" -c "import tamaas, numpy; print('tamaas', tamaas.__version__, 'numpy', numpy.__version__)"
