"""The ``gfins`` command (entry point ``gfins_fmi.cli:main``): the parser
(:mod:`~gfins_fmi.cli.parser`, options of :mod:`~gfins_fmi.cli.options`), one module per
command (``solve9``, ``navigate``, ``gfnav``, ``integrate``, ``calibrate``, ``align``,
``cosim``, ``analyze``, ``reproduce``, ``demo``, ``validate`` with ``info``), and what they
share: reading and writing files (``files``) and the initial state from options
(``initial``)."""
from __future__ import annotations

import importlib
import sys

from gfins_fmi._lib import GfinsError
from gfins_fmi.cli.parser import build_parser

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    parser, parsers = build_parser()
    args = parser.parse_args(argv)
    problem = args.check(args) if args.check else None
    if problem:   # a combination of options: refused at parse time too
        parsers[args.command].error(problem)
    try:
        # the chosen command's module only: importing all of them (and the whole package
        # with them) would make `gfins --help` ~1.7x slower (tests/repository/test_source_audit.py)
        command = importlib.import_module(f"gfins_fmi.cli.{args.module}")
        return getattr(command, args.function)(args)
    except (ValueError, TypeError, OSError, ImportError, GfinsError) as exc:
        print(f"gfins {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # the record commands write beside the output's name and rename when complete
        kept = f"; {args.output} left as it was" if getattr(args, "output", None) else ""
        print(f"gfins {args.command}: interrupted{kept}", file=sys.stderr)
        return 130
