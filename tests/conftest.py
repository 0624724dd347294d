"""What several test files share: the checkout's root, the command line run in-process or as a
child process, and which tests count as slow.

`ROOT` and `run_theoria` are plain names (`from conftest import ROOT`) for use at module level;
`cli` and `cli_process` are the fixtures most tests want.

`pytest -m "not slow"` is the quick suite; CI and `scripts/test.sh` run everything. A test is
marked slow where it is written when it took more than about 5 s in `pytest --durations` on the
shared 2-core machine (with others' jobs running); the browser tests, which start Chromium, are
slow as a group (marked here, so their files need not say it).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def run_theoria(*argv, cwd=ROOT, timeout=3600) -> subprocess.CompletedProcess:
    """`python -m theoria.app.cli ARGV...` as a child process (text output captured). The timeout
    only guards CI against a hang; it is no speed requirement."""
    return subprocess.run([sys.executable, "-m", "theoria.app.cli", *map(str, argv)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("browser") is not None:
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def cli(capsys):
    """Run `theoria ARGS...` in this process: (exit code, stdout, stderr)."""
    from theoria.app.cli import main

    def run(*argv):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as e:  # argparse's own refusals (a flag's type) exit 2 from within
            code = e.code
        out, err = capsys.readouterr()
        return code, out, err

    return run


@pytest.fixture
def cli_process():
    """Run `theoria ARGS...` as a child process from the checkout's root: (exit code, stdout, stderr)."""

    def run(*argv, **kw):
        p = run_theoria(*argv, **kw)
        return p.returncode, p.stdout, p.stderr

    return run
