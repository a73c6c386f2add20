#!/usr/bin/env bash
# Build and test the Python package as a user would, in a fresh virtualenv:
#   python3 -m venv; pip install maturin numpy pytest mypy tamaas==2.9.0 SurfaceTopography
#   (mypy for the stub check; tamaas and SurfaceTopography only for the side-by-side tests,
#   never dependencies); pip install ./python (maturin builds the abi3 wheel); stubtest of
#   the type stubs against the built module; pytest python/tests (identity with the CLI
#   binary, tamaas, SurfaceTopography, bad input).
# Usage: python/ci-test.sh   (from anywhere; needs target/release/asperity, built by
# `cargo test --release`, or ASPERITY_BIN). Called by .ci/run. The virtualenv is removed at exit.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
venv=$(mktemp -d /tmp/asperity-python-ci.XXXXXX)
trap 'rm -rf "$venv"' EXIT
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet maturin numpy pytest mypy "tamaas==2.9.0" SurfaceTopography
"$venv/bin/pip" install --quiet "$repo/python"
cd "$repo"
"$venv/bin/python" -c 'import asperity; print("asperity", asperity.__version__, "from", asperity.__file__)'
# The hand-written stubs must describe the compiled module: every name, signature, default and
# property (python/stubtest-allowlist.txt lists what stubtest cannot judge, with reasons).
"$venv/bin/python" -m mypy.stubtest asperity --allowlist python/stubtest-allowlist.txt
"$venv/bin/python" -m pytest python/tests -q -rs
