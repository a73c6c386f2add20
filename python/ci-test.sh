#!/usr/bin/env bash
# Build and test the Python package as a user would, in a fresh virtualenv:
#   python3 -m venv; pip install maturin numpy pytest tamaas==2.9.0 (tamaas only for the
#   side-by-side test, never a dependency); pip install ./python (maturin builds the abi3
#   wheel); pytest python/tests (identity with the CLI binary, tamaas, bad input).
# Usage: python/ci-test.sh   (from anywhere; needs target/release/asperity, built by
# `cargo test --release`, or ASPERITY_BIN). Called by .ci/run. The virtualenv is removed at exit.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
venv=$(mktemp -d /tmp/asperity-python-ci.XXXXXX)
trap 'rm -rf "$venv"' EXIT
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet maturin numpy pytest "tamaas==2.9.0"
"$venv/bin/pip" install --quiet "$repo/python"
cd "$repo"
"$venv/bin/python" -c 'import asperity; print("asperity", asperity.__version__, "from", asperity.__file__)'
"$venv/bin/python" -m pytest python/tests -q -rs
