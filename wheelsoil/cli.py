"""The ``wheelsoil`` command line: one parser, thin subcommands.

Each sub-package contributes its subcommands through a ``register(subparsers)``
function in its ``cli`` module; handlers import their heavy dependencies lazily
so that ``wheelsoil --help`` stays fast. Every handler is a thin wrapper over a
library function a notebook user can call directly.
"""

from __future__ import annotations

import argparse
import sys
from importlib import import_module

from wheelsoil import __version__

#: Modules whose ``register(subparsers)`` adds subcommands, in --help order.
_COMMAND_MODULES = (
    "wheelsoil.daq.cli",
    "wheelsoil.processing.cli",
    "wheelsoil.model.cli",
    "wheelsoil.pipeline",
    "wheelsoil.simulate",
)

_EPILOG = """\
typical field-to-report flow:
  wheelsoil log --bus socketcan:can0 --bus socketcan:can1 -o run.mcap
  wheelsoil info run.mcap
  wheelsoil process run.mcap -o signals.csv
  wheelsoil fit run.mcap --terrain clay -o report/

offline:
  wheelsoil import candump.log -o run.mcap      (also .asc, .blf, .trc)
  wheelsoil simulate --terrain sand --effect lyasko -o sim.mcap
  wheelsoil predict --terrain clay --model wong --load 11000 --slip 0.1,0.5
  wheelsoil terrains

Run 'wheelsoil COMMAND --help' for each command's options.
"""


def build_parser() -> argparse.ArgumentParser:
    """Build the full ``wheelsoil`` argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="wheelsoil",
        description="Wheel-soil field testing: CAN capture, MCAP recordings, decode, "
        "time-sync, slip, Wong's terramechanics model, Gauss-Newton fitting and diagnosis.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"wheelsoil {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in _COMMAND_MODULES:
        try:
            module = import_module(name)
        except ModuleNotFoundError as exc:  # a sub-package not built yet
            if exc.name != name:
                raise
            continue
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``wheelsoil`` console script; returns the exit code.

    Errors a user can fix (bad input files, bad options: ``ValueError``,
    ``OSError``) are printed as one ``wheelsoil: error: ...`` line, exit 2;
    Ctrl-C exits 130.
    """
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    args.argv = argv  # the command as typed: reports record it (provenance) so it can be re-run
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help()
        return 2
    try:
        return int(func(args) or 0)
    except BrokenPipeError:  # output piped into head/less that closed early
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("wheelsoil: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError) as exc:
        print(f"wheelsoil {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
