"""Real-vcan0 acceptance tests, run inside a qemu guest (issue 4).

The host kernel (and CI's) has no AF_CAN.  The module fixture boots one qemu
guest (Debian's stock kernel under TCG, the host's / read-only over 9p, see
``tests/vm/vcanvm.py``) that runs pytest on ``tests/vm/guest_*.py`` with this
test run's own Python (``sys.executable``), so the same virtualenv and checkout
are tested; the files run as parallel groups, each in its own network
namespace with its own ``vcan0``/``vcan1``.  Each guest test is mirrored here as one parametrized test that
passes, fails (with the guest's report) or skips (with the guest's reason).
Without qemu, a Debian kernel with vcan, or busybox-static, everything here
skips with the reason; ``make vm-packages`` installs them (Debian, as root).

Run only these:  ``python -m pytest -q -rs -m vm tests/test_vm_vcan.py``
(add ``-rP`` to see guest timings and the burst-test numbers).
"""

import re
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
VMDIR = REPO / "tests" / "vm"
sys.path.insert(0, str(VMDIR))
import vcanvm  # noqa: E402

pytestmark = pytest.mark.vm

GUEST_FILES = sorted(VMDIR.glob("guest_*.py"))
#: Guest test files run as parallel pytest processes (own network namespace and vcan0/vcan1
#: each); files not listed join the last group. The replay test's two `wheelsoil` processes
#: spend ~1-2 min importing under TCG, so the other tests run beside them.
PARALLEL_GROUPS = {"replay": ["guest_replay_log.py"], "socketcan": ["guest_socketcan.py", "guest_logger_burst.py"]}
#: qemu is killed after this long; the guest normally finishes in about 2 min (TCG).
VM_TIMEOUT_S = 480


def _guest_test_ids():
    """``guest_file.py::test_name`` for every guest test function (read without importing)."""
    for f in GUEST_FILES:
        for name in re.findall(r"^def (test_\w+)\(", f.read_text(), re.M):
            yield f"{f.name}::{name}"


def _parse_junit(path: Path) -> list[dict]:
    """Test cases of a pytest junit-xml (xunit1) file as dicts."""
    cases = []
    for tc in ET.parse(path).getroot().iter("testcase"):
        outcome, text = "passed", ""
        for kind in ("failure", "error", "skipped"):
            el = tc.find(kind)
            if el is not None:
                outcome = "failed" if kind in ("failure", "error") else "skipped"
                text = (el.get("message") or "") + "\n" + (el.text or "")
                break
        props = {p.get("name"): p.get("value") for p in tc.iter("property")}
        cases.append(dict(file=tc.get("classname", "").rsplit(".", 1)[-1] + ".py", name=tc.get("name"),
                          outcome=outcome, text=text, props=props, seconds=float(tc.get("time") or 0)))
    return cases


@pytest.fixture(scope="module")
def guest_session(tmp_path_factory):
    """Boot the VM once, run all guest tests, return (VmResult, [test case dicts])."""
    reason = vcanvm.missing_prerequisites()
    if reason:
        pytest.skip(f"qemu vcan VM unavailable: {reason}")
    work = tmp_path_factory.mktemp("vcanvm")
    groups = {name: [] for name in PARALLEL_GROUPS}
    for f in GUEST_FILES:
        name = next((g for g, fs in PARALLEL_GROUPS.items() if f.name in fs), list(groups)[-1])
        groups[name].append(str(f.relative_to(REPO)))
    cmd = vcanvm.parallel_pytest_command(sys.executable, {g: fs for g, fs in groups.items() if fs})
    t0 = time.monotonic()
    result = vcanvm.run_in_vm(cmd, work, cwd=str(REPO), timeout=VM_TIMEOUT_S)
    cases = [c for junit in sorted(result.outdir.glob("junit-*.xml")) for c in _parse_junit(junit)]
    print(f"VM: {time.monotonic() - t0:.1f} s wall, guest exit {result.returncode}")
    return result, cases


def test_vm_boots_and_runs_guest_tests(guest_session):
    result, cases = guest_session
    print(result.console)
    assert not result.timed_out, f"VM timed out:\n{result.tail()}"
    assert "VCANVM: vcan0 up" in result.console, result.tail()
    assert result.returncode in (0, 1), f"guest pytest did not complete (exit {result.returncode}):\n{result.tail()}"
    assert cases, f"guest wrote no junit report:\n{result.tail()}"


@pytest.mark.parametrize("case_id", list(_guest_test_ids()))
def test_in_guest(guest_session, case_id, record_property):
    result, cases = guest_session
    fname, name = case_id.split("::")
    mine = [c for c in cases if c["file"] == fname and re.fullmatch(re.escape(name) + r"(\[.*\])?", c["name"])]
    if not mine:
        pytest.fail(f"{case_id} did not run in the guest (exit {result.returncode}):\n{result.tail()}")
    for c in mine:
        for k, v in c["props"].items():
            record_property(k, v)
            print(f"{c['name']}: {k} = {v}")
        print(f"{c['name']}: {c['outcome']} in {c['seconds']:.1f} s (guest)")
    failed = [c for c in mine if c["outcome"] == "failed"]
    if failed:
        pytest.fail("\n\n".join(f"guest {c['name']} failed:\n{c['text']}" for c in failed), pytrace=False)
    if all(c["outcome"] == "skipped" for c in mine):
        pytest.skip("in the guest: " + mine[0]["text"].strip().splitlines()[0])
