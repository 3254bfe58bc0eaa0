# Shared by the Python tests: the CLI to compare with, and the repository's cases.
import json
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("KNOTWORK_SOURCE_DIR") or pathlib.Path(__file__).resolve().parents[2])
BINARY = os.environ.get("KNOTWORK_BINARY", str(SOURCE / "build/app/knotwork"))
CASES = SOURCE / "cases"


def cli(args, cwd=None):
    """Runs the knotwork binary; returns (exit code, stdout, stderr)."""
    p = subprocess.run([BINARY, *args], capture_output=True, text=True, cwd=cwd, timeout=600)
    return p.returncode, p.stdout, p.stderr


def cli_json(args, cwd=None):
    quiet = [] if args[0] in ("basis", "dimension") else ["-q"]
    code, out, err = cli([*args, "--json", *quiet], cwd=cwd)
    assert code == 0, err
    return json.loads(out)


@pytest.fixture
def cases():
    return CASES
