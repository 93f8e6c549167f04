"""Host-side checks of the qemu vcan harness (tests/vm/vcanvm.py) that need no qemu."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "vm"))
import vcanvm  # noqa: E402


@pytest.mark.skipif(shutil.which("cpio") is None, reason="GNU cpio not installed (used only to check the archive)")
def test_cpio_newc_archive_extracts_with_gnu_cpio(tmp_path):
    payload = bytes(range(256)) * 3 + b"x"  # length not a multiple of 4: padding exercised
    archive = vcanvm._cpio_newc([
        ("bin", 0o040755, b""),
        ("bin/busybox", 0o100755, payload),
        ("bin/sh", 0o120777, "busybox"),
        ("init", 0o100755, "#!/bin/sh\necho hi\n"),
    ])
    out = tmp_path / "x"
    out.mkdir()
    subprocess.run(["cpio", "-idm", "--quiet"], input=archive, cwd=out, check=True)
    assert (out / "bin/busybox").read_bytes() == payload
    assert (out / "bin/sh").is_symlink() and (out / "bin/sh").readlink() == Path("busybox")
    assert (out / "init").read_text() == "#!/bin/sh\necho hi\n"
    assert (out / "init").stat().st_mode & 0o777 == 0o755


def test_parallel_pytest_command_isolates_groups():
    cmd = vcanvm.parallel_pytest_command("/venv/bin/python", {"a": ["tests/vm/guest_a.py"],
                                                              "b": ["tests/vm/guest_b.py", "tests/vm/guest_c.py"]})
    lines = [ln for ln in cmd.splitlines() if ln.startswith("(unshare --net")]
    assert len(lines) == 2 and all(ln.endswith("&") for ln in lines)
    assert "junit-a.xml" in lines[0] and "guest_a.py" in lines[0] and "guest_b.py" not in lines[0]
    assert "junit-b.xml" in lines[1] and "guest_b.py" in lines[1] and "guest_c.py" in lines[1]
    for ln in lines:
        assert "ip link add dev vcan0 type vcan" in ln and "ip link add dev vcan1 type vcan" in ln
    assert "\nwait\n" in cmd and cmd.rstrip().endswith("exit $rc")


def test_missing_prerequisites_names_the_missing_tool(monkeypatch):
    monkeypatch.setattr(vcanvm.shutil, "which", lambda name: None)
    reason = vcanvm.missing_prerequisites()
    assert reason is not None and ("qemu-system-x86_64" in reason or "not a Linux host" in reason)
