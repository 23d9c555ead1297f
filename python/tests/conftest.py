"""Shared fixtures: the command-line tool (for results compared with its --json output)."""
import json
import os
import shutil
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli():
    """Runs `implicit ARGS --json` and returns the parsed result (the build's tool, from the
    IMPLICIT_CLI variable the test registration sets, else `implicit` on PATH)."""
    exe = os.environ.get("IMPLICIT_CLI") or shutil.which("implicit")
    assert exe, "set IMPLICIT_CLI to the implicit executable"

    def run(*args):
        out = subprocess.run([exe, *args, "--json"], check=True, capture_output=True, text=True)
        return json.loads(out.stdout)

    return run
