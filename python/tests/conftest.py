"""Shared fixtures: the repository and the `ilopt` binary the package is compared with.

The binary is $ILOPT_BIN, else the workspace's target/release/ilopt, else target/debug/ilopt
(f64 arithmetic is the same in both profiles). The suite fails, not skips, without one.
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def cli():
    candidates = [os.environ.get("ILOPT_BIN")] if os.environ.get("ILOPT_BIN") else []
    candidates += [REPO / "target/release/ilopt", REPO / "target/debug/ilopt"]
    binary = next((Path(c) for c in candidates if Path(c).is_file()), None)
    if binary is None:
        pytest.fail("no ilopt binary: build it (cargo build --release) or set ILOPT_BIN")

    def call(*args, ok=True):
        p = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if ok:
            assert p.returncode == 0, p.stderr
            return json.loads(p.stdout)
        assert p.returncode != 0, p.stdout
        assert p.stderr.startswith("error: "), p.stderr
        assert p.stderr.endswith("\n"), p.stderr
        return p.stderr[len("error: ") : -1]  # the message, without the newline eprintln adds

    return call
