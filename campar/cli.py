"""The ``campar`` command: argument parsing and dispatch only.

Each subcommand is a ``add_<name>(subparsers)`` function that registers its
parser and sets ``handler`` to a function in the module that owns the logic,
so every behaviour is reachable from Python without the CLI.
"""

import argparse
import sys

from . import __version__
from .errors import CamparError

# Registered subcommands, in the order ``campar --help`` lists them.
SUBCOMMANDS = []


def subcommand(add):
    SUBCOMMANDS.append(add)
    return add


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="campar",
        description="Two-parameter bifurcation maps of the cam–follower impact oscillator.",
    )
    parser.add_argument("--version", action="version", version=f"campar {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except CamparError as exc:
        print(f"campar {args.command}: {exc}", file=sys.stderr)
        return exc.exit_code


# -- subcommands -------------------------------------------------------------
# (each block: one ``@subcommand`` function; keep the logic in its own module)


if __name__ == "__main__":
    sys.exit(main())
