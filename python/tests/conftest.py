"""Fixtures of the Python tests: the CLI binary (for the identity tests) and the shared data.

ASPERITY_BIN names the `asperity` binary (default: <repo>/target/release/asperity, or under
CARGO_TARGET_DIR). ASPERITY_DATA_DIR names the shared reference data (default ../shared/data
beside the repository); tests needing it skip when it is absent, unless ASPERITY_REQUIRE_DATA=1.
"""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli():
    """Run the CLI: ``cli(*args)`` returns the CompletedProcess; raises on a non-zero exit."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    binary = Path(os.environ.get("ASPERITY_BIN", target / "release" / "asperity"))
    if not binary.exists():
        pytest.fail(f"asperity binary {binary} not found: build it (cargo build --release) or set ASPERITY_BIN")

    def run(*args, check=True):
        r = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError(f"asperity {' '.join(map(str, args))} failed:\n{r.stderr}")
        return r

    return run


@pytest.fixture(scope="session")
def data_dir():
    d = Path(os.environ.get("ASPERITY_DATA_DIR", REPO.parent / "shared" / "data"))
    return d


@pytest.fixture
def data_file(data_dir):
    """``data_file("film/x.png")``: the path, or a skip (a failure with ASPERITY_REQUIRE_DATA=1)."""

    def get(relative):
        p = data_dir / relative
        if not p.exists():
            msg = f"reference data file {p} not found (set ASPERITY_DATA_DIR)"
            if os.environ.get("ASPERITY_REQUIRE_DATA") == "1":
                pytest.fail(msg + " and ASPERITY_REQUIRE_DATA=1")
            pytest.skip(msg)
        return p

    return get


@pytest.fixture(scope="session")
def repo():
    return REPO
