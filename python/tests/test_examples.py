"""The examples run (shortened)."""

import pathlib
import subprocess
import sys

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def run(script, *args):
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *args],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_walk_hex18(tmp_path):
    record = tmp_path / "walk.rrd"
    out = run("walk_hex18.py", "--duration", "3", "--record", str(record))
    assert "walked" in out and record.stat().st_size > 0


def test_random_policy():
    out = run("random_policy.py", "--episodes", "2", "--duration", "1")
    assert out.count("episode") == 2
