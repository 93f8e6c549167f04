"""Boot a throw-away QEMU guest with a real ``vcan0`` and run one shell command in it.

This machine's (and CI's) kernel has no AF_CAN; Debian's stock kernel has it as
modules.  The guest boots that kernel under qemu TCG with no disk: a tiny
initramfs (busybox-static plus the virtio/9p modules) mounts the host's ``/``
read-only over virtio-9p and ``switch_root``s into it, so the guest runs the
host's own Python, virtualenv and checkout.  The guest init loads ``can``,
``can_raw``, ``vcan``, brings up ``vcan0`` and ``vcan1``, runs the command, prints
``VCANVM_EXIT=<rc>`` and powers off.  A second, writable 9p share (``/run/out``
in the guest) carries files out; the guest's tmpfs is on ``/run`` (never over
``/tmp``, which would hide paths of the host such as pytest's temp dirs).

Packages (Debian): qemu-system-x86 linux-image-amd64 busybox-static can-utils
(``make vm-packages``).  Nothing is installed here; :func:`missing_prerequisites`
names what is missing so callers can skip.  Recipe: ../shared/vcan-vm/ (about
20 s from qemu start to power-off on a 2-core machine).
"""

from __future__ import annotations

import dataclasses
import glob
import gzip
import lzma
import os
import re
import shlex
import shutil
import subprocess
import time
from pathlib import Path

#: Modules the initramfs needs to mount the host root (their dependencies are added).
INITRAMFS_MODULES = ("virtio_pci", "9pnet_virtio", "9p")
#: Modules the guest loads from the host's /lib/modules once it runs on the host root.
GUEST_MODULES = ("can", "can_raw", "vcan")
#: Virtual CAN interfaces created in the guest (two, like the vehicle's two buses).
VCAN_INTERFACES = ("vcan0", "vcan1")

_INITRAMFS_INIT = """#!/bin/sh
# PID 1 of the initramfs: load virtio/9p, mount the host's / read-only, switch_root.
mount -t proc proc /proc
mount -t devtmpfs dev /dev
for m in $(cat /mods/order); do insmod /mods/$m || echo "VCANVM: insmod $m failed"; done
GINIT=
for a in $(cat /proc/cmdline); do case $a in vcanvm.init=*) GINIT=${a#vcanvm.init=};; esac; done
mount -t 9p -o ro,trans=virtio,version=9p2000.L,msize=512000,cache=loose root /newroot \\
  || { echo "VCANVM: 9p root mount failed"; echo o > /proc/sysrq-trigger; sleep 10; }
umount /proc /dev
exec switch_root /newroot /bin/sh "$GINIT"
"""

_GUEST_INIT = """#!/bin/sh
# PID 1 in the guest, running from the host's root over 9p (read-only).
export PATH={path}
export TMPDIR=/run HOME=/run PYTHONDONTWRITEBYTECODE=1 {env}
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
mount -t tmpfs -o size=60% tmp /run
mkdir -p /run/out && mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 out /run/out \\
  || echo "VCANVM: out share mount failed"
echo "VCANVM: kernel $(uname -r), $(nproc) cpu, up $(cut -d' ' -f1 /proc/uptime) s"
for m in {modules}; do modprobe $m || echo "VCANVM: modprobe $m failed"; done
for i in {interfaces}; do ip link add dev $i type vcan && ip link set up $i && echo "VCANVM: $i up"; done
cd {cwd} && sh {cmd} < /dev/null; rc=$?
echo "VCANVM_EXIT=$rc (up $(cut -d' ' -f1 /proc/uptime) s)"
sync; echo o > /proc/sysrq-trigger; sleep 30
"""

#: Host environment variables passed into the guest when set.
PASSED_ENV = ("PYTHONPATH", "VIRTUAL_ENV", "LANG", "LC_ALL")


@dataclasses.dataclass
class VmResult:
    """Outcome of one guest run.

    Attributes:
        returncode: exit code of the guest command, or -1 when the guest never
            reported one (boot failure, timeout, crash).
        console: the guest's serial console plus qemu's stderr (str).
        outdir: host directory that was the guest's writable ``/run/out``.
        seconds: wall time from qemu start to its exit (s).
        timed_out: True if qemu was killed at the timeout.
    """

    returncode: int
    console: str
    outdir: Path
    seconds: float
    timed_out: bool = False

    def tail(self, nchars: int = 4000) -> str:
        """The last ``nchars`` characters of the console, for failure messages."""
        return self.console[-nchars:]


def find_kernel() -> tuple[Path, str]:
    """Newest readable ``/boot/vmlinuz-*`` whose ``/lib/modules`` has vcan and 9p.

    Returns:
        ``(kernel_image, kernel_version)``.

    Raises:
        RuntimeError: with the reason when none qualifies.
    """
    images = sorted(glob.glob("/boot/vmlinuz-*"), reverse=True)
    if not images:
        raise RuntimeError("no /boot/vmlinuz-* (apt-get install linux-image-amd64)")
    for img in images:
        kver = img[len("/boot/vmlinuz-"):]
        dep = _modules_dep(kver)
        if not dep or not {"vcan", "9p", "9pnet_virtio"} <= set(dep):
            continue
        if not os.access(img, os.R_OK):
            raise RuntimeError(f"{img} is not readable by this user (run as root)")
        return Path(img), kver
    raise RuntimeError("no /boot/vmlinuz-* with vcan and 9p modules in /lib/modules (apt-get install linux-image-amd64)")


def _modules_dep(kver: str) -> dict[str, tuple[str, list[str]]]:
    """``modules.dep`` of a kernel as {module name: (path, [dependency names])}."""
    path = Path("/lib/modules", kver, "modules.dep")
    if not path.is_file():
        return {}
    out = {}
    for line in path.read_text().splitlines():
        mod, _, deps = line.partition(":")
        if mod:
            out[_modname(mod)] = (str(path.parent / mod), [_modname(d) for d in deps.split()])
    return out


def _modname(path: str) -> str:
    return re.sub(r"\.ko(\.(xz|gz|zst))?$", "", os.path.basename(path)).replace("-", "_")


def _static_busybox() -> str:
    """Path of a statically linked busybox, or raise RuntimeError."""
    for cand in (shutil.which("busybox"), "/bin/busybox", "/usr/bin/busybox"):
        if cand and os.path.isfile(cand):
            with open(cand, "rb") as f:
                head = f.read(8192)
            if b"ld-linux" not in head and b"/lib/ld-" not in head:
                return cand
    raise RuntimeError("no statically linked busybox (apt-get install busybox-static)")


def missing_prerequisites() -> str | None:
    """Why the VM cannot run here, or None when it can (installs nothing)."""
    if not os.path.exists("/proc/self") or os.uname().sysname != "Linux":
        return "not a Linux host"
    if shutil.which("qemu-system-x86_64") is None:
        return "qemu-system-x86_64 not found (apt-get install qemu-system-x86; make vm-packages)"
    try:
        _, kver = find_kernel()
        _static_busybox()
    except RuntimeError as exc:
        return str(exc)
    zst = [m for m in _module_order(kver, INITRAMFS_MODULES) if m.endswith(".zst")]
    if zst:
        return f"zstd-compressed kernel modules ({os.path.basename(zst[0])}) are not supported by this harness"
    for tool in ("ip", "modprobe", "mount", "unshare"):
        if not any(os.access(os.path.join(d, tool), os.X_OK) for d in _guest_path().split(":")):
            return f"'{tool}' not found on the host root the guest boots from"
    return None


def _guest_path() -> str:
    dirs = os.environ.get("PATH", "").split(":") + "/usr/local/sbin /usr/local/bin /usr/sbin /usr/bin /sbin /bin".split()
    return ":".join(dict.fromkeys(d for d in dirs if d))


def _module_order(kver: str, names) -> list[str]:
    """Module files for ``names`` and their dependencies, dependencies first."""
    dep = _modules_dep(kver)
    order: list[str] = []

    def visit(name: str) -> None:
        if name not in dep:
            return  # built into the kernel (modules.builtin) or absent: nothing to load
        path, deps = dep[name]
        for d in deps:
            visit(d)
        if path not in order:
            order.append(path)

    for n in names:
        visit(n.replace("-", "_"))
    return order


def _read_module(path: str) -> bytes:
    """A kernel module's ELF bytes (busybox insmod wants them uncompressed)."""
    raw = Path(path).read_bytes()
    if path.endswith(".xz"):
        return lzma.decompress(raw)
    if path.endswith(".gz"):
        return gzip.decompress(raw)
    if path.endswith(".zst"):
        raise RuntimeError(f"{path}: zstd-compressed module, not supported by this harness")
    return raw


def _cpio_newc(entries) -> bytes:
    """An uncompressed cpio archive in the kernel's ``newc`` format.

    ``entries``: iterable of ``(name, mode, data: bytes | str)``; for symlinks
    ``data`` is the link target.  Source: Linux Documentation/driver-api/early-userspace/buffer-format.rst.
    """
    out = bytearray()
    ino = 1
    for name, mode, data in list(entries) + [("TRAILER!!!", 0, b"")]:
        data = data.encode() if isinstance(data, str) else data
        bname = name.encode() + b"\0"
        fields = (ino, mode, 0, 0, 1, 0, len(data), 0, 0, 0, 0, len(bname), 0)
        out += b"070701" + b"".join(b"%08X" % v for v in fields) + bname
        out += b"\0" * (-len(out) % 4) + data
        out += b"\0" * (-len(out) % 4)
        ino += 1
    return bytes(out)


def build_initramfs(workdir: Path, kver: str) -> Path:
    """Write ``workdir/initramfs.cpio`` (busybox + virtio/9p modules + init) and return its path.

    Raises:
        RuntimeError: if busybox is not static or a module cannot be read.
    """
    busybox = Path(_static_busybox()).read_bytes()
    mods = _module_order(kver, INITRAMFS_MODULES)
    entries = [(d, 0o040755, b"") for d in ("bin", "mods", "newroot", "proc", "dev")]
    entries.append(("bin/busybox", 0o100755, busybox))
    for applet in ("sh", "mount", "umount", "insmod", "switch_root", "cat", "echo", "sleep"):
        entries.append((f"bin/{applet}", 0o120777, "busybox"))
    names = []
    for path in mods:
        name = _modname(path) + ".ko"
        entries.append((f"mods/{name}", 0o100644, _read_module(path)))
        names.append(name)
    entries.append(("mods/order", 0o100644, "\n".join(names) + "\n"))
    entries.append(("init", 0o100755, _INITRAMFS_INIT))
    img = Path(workdir) / "initramfs.cpio"
    img.write_bytes(_cpio_newc(entries))
    return img


def run_in_vm(
    cmd: str,
    workdir: Path,
    *,
    cwd: str = "/",
    timeout: float = 240.0,
    mem_mb: int = 1024,
    cpus: int = 2,
    env: dict[str, str] | None = None,
) -> VmResult:
    """Boot a fresh guest with ``vcan0`` and ``vcan1`` up, run shell command ``cmd`` in ``cwd``, power off.

    Args:
        cmd: shell command (run by the host's /bin/sh inside the guest, as root).
        workdir: empty host directory the guest can see (e.g. a pytest temp dir
            under /tmp; the host root is shared, so any path works); holds the
            initramfs, scripts, ``console.log`` and ``out/`` (the guest's writable ``/run/out``).
        cwd: guest working directory (a host path; read-only in the guest).
        timeout: seconds before qemu is killed (TCG is slow: ``import can``
            takes 2-3 s in the guest).
        mem_mb, cpus: guest memory (MiB) and vCPUs (multi-threaded TCG).
        env: extra environment variables for the command.

    Returns:
        :class:`VmResult` (``returncode`` -1 when the guest never reported one).

    Raises:
        RuntimeError: when prerequisites are missing (see :func:`missing_prerequisites`).
    """
    reason = missing_prerequisites()
    if reason:
        raise RuntimeError(reason)
    kernel, kver = find_kernel()
    workdir = Path(workdir).resolve()
    outdir = workdir / "out"
    outdir.mkdir(parents=True, exist_ok=True)
    (workdir / "cmd.sh").write_text(cmd + "\n")
    envs = {k: os.environ[k] for k in PASSED_ENV if k in os.environ}
    envs.update(env or {})
    (workdir / "guest_init.sh").write_text(
        _GUEST_INIT.format(
            path=shlex.quote(_guest_path()),
            env=" ".join(f"{k}={shlex.quote(v)}" for k, v in envs.items()),
            modules=" ".join(GUEST_MODULES),
            interfaces=" ".join(VCAN_INTERFACES),
            cwd=shlex.quote(cwd),
            cmd=shlex.quote(str(workdir / "cmd.sh")),
        )
    )
    initrd = build_initramfs(workdir, kver)
    argv = [
        "qemu-system-x86_64", "-accel", "tcg,thread=multi", "-cpu", "max",
        "-m", str(mem_mb), "-smp", str(cpus),
        "-nodefaults", "-no-user-config", "-display", "none", "-serial", "stdio", "-no-reboot",
        "-kernel", str(kernel), "-initrd", str(initrd),
        "-append", f"console=ttyS0 quiet panic=-1 vcanvm.init={workdir / 'guest_init.sh'}",
        "-fsdev", "local,id=r,path=/,security_model=none,readonly=on,multidevs=remap",
        "-device", "virtio-9p-pci,fsdev=r,mount_tag=root",
        "-fsdev", f"local,id=o,path={outdir},security_model=none,multidevs=remap",
        "-device", "virtio-9p-pci,fsdev=o,mount_tag=out",
    ]
    t0 = time.monotonic()
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    timed_out = False
    try:
        raw, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        raw, _ = proc.communicate()
        timed_out = True
    console = raw.decode("utf-8", "replace").replace("\r\n", "\n")
    if timed_out:
        console += f"\nVCANVM: qemu killed after {timeout:.0f} s timeout\n"
    (workdir / "console.log").write_text(console)
    m = re.search(r"^VCANVM_EXIT=(\d+)", console, re.M)
    return VmResult(int(m.group(1)) if m else -1, console, outdir, time.monotonic() - t0, timed_out)


def parallel_pytest_command(python: str, groups: dict[str, list[str]], *, pytest_args=(),
                            interfaces=VCAN_INTERFACES) -> str:
    """Guest shell command running one pytest process per group, all at once.

    Each group runs in its own network namespace (``unshare --net``) with its
    own ``vcan0``/``vcan1``, so groups cannot see each other's frames and every
    test can use the usual interface names.  Under TCG, Python start-up is
    CPU-bound; two groups keep both vCPUs busy.

    Args:
        python: interpreter path (the host's ``sys.executable``; same path in the guest).
        groups: group name -> test file paths (relative to the guest cwd).
        pytest_args: extra pytest arguments for every group.
        interfaces: vcan interfaces created in each namespace.

    Returns:
        A ``sh`` script: writes ``/run/out/junit-<group>.xml`` and
        ``/run/out/<group>.log``, prints each log, exits with the largest exit code.
    """
    q = shlex.quote
    links = " && ".join(f"ip link add dev {i} type vcan && ip link set up {i}" for i in interfaces)
    lines = []
    for name, files in groups.items():
        argv = [python, "-m", "pytest", "-v", "-rA", "--color=no", "-p", "no:cacheprovider",
                "-p", "no:hypothesispytest", "-o", "junit_family=xunit1",
                f"--junitxml=/run/out/junit-{name}.xml", f"--basetemp=/run/pytest-{name}", *pytest_args, *files]
        inner = f"{links} && exec {' '.join(q(a) for a in argv)}"
        lines.append(f"(unshare --net sh -c {q(inner)} > /run/out/{name}.log 2>&1; echo $? > /run/out/{name}.rc) &")
    lines.append("wait")
    lines.append("rc=0")
    for name in groups:
        lines.append(f'r=$(cat /run/out/{name}.rc); echo "=== guest pytest group {name}: exit $r"; '
                     f'cat /run/out/{name}.log; [ "$r" -gt "$rc" ] && rc=$r')
    lines.append("exit $rc")
    return "\n".join(lines)


def main(argv=None) -> int:
    """``python tests/vm/vcanvm.py [--timeout S] 'shell command'``: run it in a fresh guest."""
    import argparse
    import sys
    import tempfile

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                epilog="example: python tests/vm/vcanvm.py 'candump -n 3 vcan0 & cangen -n 3 vcan0; wait'")
    p.add_argument("command", help="shell command run as root in the guest (cwd: this checkout)")
    p.add_argument("--timeout", type=float, default=300.0, help="seconds before qemu is killed (default 300)")
    args = p.parse_args(argv)
    reason = missing_prerequisites()
    if reason:
        print(f"vcanvm: cannot run the VM: {reason}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="vcanvm-") as work:
        res = run_in_vm(args.command, Path(work), cwd=str(Path(__file__).resolve().parents[2]), timeout=args.timeout)
    print(res.console)
    print(f"vcanvm: guest exit {res.returncode}, {res.seconds:.1f} s")
    return 0 if res.returncode == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
