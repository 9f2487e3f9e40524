# The examples run, headless (matplotlib's Agg backend), and write their figures: they cannot rot.
import os
import pathlib
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_and_writes_its_figure(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, str(script), str(tmp_path), "--size", "64"], capture_output=True, text=True, env=env, timeout=600)
    assert p.returncode == 0, p.stderr
    figure = tmp_path / f"{script.stem}.png"
    assert figure.is_file() and figure.stat().st_size > 1000
    assert figure.read_bytes().startswith(b"\x89PNG")
