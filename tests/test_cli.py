"""The command line parses and teaches."""

import subprocess
import sys


def test_help_lists_commands():
    out = subprocess.run([sys.executable, "-m", "wheelsoil", "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "wheelsoil" in out.stdout
