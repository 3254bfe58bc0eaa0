# Shared by the Python tests: the CLI to compare with, and the repository's cases.
import json
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("KNOTWORK_SOURCE_DIR") or pathlib.Path(__file__).resolve().parents[2])
BINARY = os.environ.get("KNOTWORK_BINARY", str(SOURCE / "build/app/knotwork"))
CASES = SOURCE / "cases"


# The sanitizer build preloads clang's shared ASan runtime into this interpreter for the
# module (tests/CMakeLists.txt); the binary carries its own, and the two must not meet.
CLI_ENV = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}


def cli(args, cwd=None):
    """Runs the knotwork binary; returns (exit code, stdout, stderr)."""
    p = subprocess.run([BINARY, *args], capture_output=True, text=True, cwd=cwd, timeout=600, env=CLI_ENV)
    return p.returncode, p.stdout, p.stderr


def cli_json(args, cwd=None):
    quiet = [] if args[0] in ("basis", "dimension") else ["-q"]
    code, out, err = cli([*args, "--json", *quiet], cwd=cwd)
    assert code == 0, err
    return json.loads(out)


@pytest.fixture
def cases():
    return CASES
