# Shared set-up of the Python module's tests: the module from build/python (PYTHONPATH, set by
# CTest), the mesolab binary for comparisons with the command line, and the repository's presets.
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
PRESETS = ROOT / "presets"
BINARY = os.environ.get("MESOLAB_BINARY", str(ROOT / "build" / "mesolab"))


@pytest.fixture(scope="session")
def mesolab():
    import mesolab as m
    return m


@pytest.fixture(scope="session")
def wb(mesolab):
    return mesolab.Workbench()


def cli(*args, check=False):
    """Run the mesolab binary; returns (exit status, stdout, stderr)."""
    p = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"mesolab {' '.join(map(str, args))} failed ({p.returncode}): {p.stderr}")
    return p.returncode, p.stdout, p.stderr


def cli_error(*args):
    """The CLI's message for exit status 2, without its 'mesolab: error: ' prefix."""
    code, _, err = cli(*args)
    assert code == 2, err
    line = [l for l in err.splitlines() if l.startswith("mesolab: error: ")][-1]
    return line[len("mesolab: error: "):]
