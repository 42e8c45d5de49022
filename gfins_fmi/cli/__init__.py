"""The ``gfins`` command (entry point ``gfins_fmi.cli:main``): the parser
(:mod:`~gfins_fmi.cli.parser`, options of :mod:`~gfins_fmi.cli.options`), one module per
command (``solve9``, ``navigate``, ``gfnav``, ``integrate``, ``calibrate``, ``align``,
``cosim``, ``analyze``, ``reproduce``, ``demo``, ``validate`` with ``info``), and what they
share: reading and writing files (``files``) and the initial state from options
(``initial``)."""
from __future__ import annotations

import contextlib
import importlib
import re
import signal
import sys
import threading
import warnings

from gfins_fmi._lib import GfinsError
from gfins_fmi.cli.parser import build_parser

__all__ = ["main", "Terminated", "Failed"]

#: a value that starts with '-' and is a number or a list of them (``-0.301,0.2,1``,
#: ``-1e-3``): argparse takes it for an option unless written ``--opt=-0.3,...``
_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d)[0-9eE.+\-,:]*$")


class Failed(Exception):
    """A command failed while it ran (not a refused option or input): ``gfins CMD:
    failed: ...``, exit status 1. The message says what was written before it."""


def _negative_values_joined(argv: list[str]) -> list[str]:
    """``--opt -0.3,1,2`` as ``--opt=-0.3,1,2``: negative numbers and vectors as values,
    the way people type them (before, argparse refused them: "expected one argument")."""
    out: list[str] = []
    for tok in argv:
        prev = out[-1] if out else ""
        if (_NEGATIVE_VALUE.match(tok) and prev.startswith("--") and "=" not in prev
                and prev != "--"):
            out[-1] = f"{prev}={tok}"
        else:
            out.append(tok)
    return out


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, like Ctrl-C's KeyboardInterrupt: the same
    clean-up runs (no temporaries, the previous outputs kept)."""


def _terminate(signum, frame):
    raise Terminated()


@contextlib.contextmanager
def _sigterm_raises():
    """SIGTERM raises :class:`Terminated` while a command runs (main thread only; the
    previous handler is put back)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)   # recorded before a pending one can run
    try:
        signal.signal(signal.SIGTERM, _terminate)
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def _warnings_as_lines(command: str):
    """The library's warnings (plausibility, unusable measurements: UserWarning and its
    kin) shown as one line each, ``gfins CMD: warning: ...``, every time."""
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"gfins {command}: warning: {message}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", UserWarning)
        warnings.showwarning = show
        yield


def _outputs_note(exc) -> str:
    note = getattr(exc, "gfins_outputs", "")
    return f"; {note}" if note else ""


def _parse(argv: list[str] | None):
    parser, parsers = build_parser()
    tokens = _negative_values_joined(sys.argv[1:] if argv is None else list(argv))
    args = parser.parse_args(tokens)
    args.argv = tokens      # what was typed: --config tells the options given from the defaults by it
    problem = args.check(args) if args.check else None
    if problem:   # a combination of options: refused at parse time too
        parsers[args.command].error(problem)
    return args


def main(argv: list[str] | None = None) -> int:
    try:
        args = _parse(argv)
    except KeyboardInterrupt:   # Ctrl-C while the options are read: nothing ran, no traceback
        print("gfins: interrupted before the command started (nothing written)", file=sys.stderr)
        return 130
    try:
        with _sigterm_raises(), _warnings_as_lines(args.command):
            # the chosen command's module only: importing all of them (and the whole package
            # with them) would make `gfins --help` ~1.7x slower (tests/repository/test_source_audit.py)
            command = importlib.import_module(f"gfins_fmi.cli.{args.module}")
            return getattr(command, args.function)(args)
    except Failed as exc:
        print(f"gfins {args.command}: failed: {exc}{_outputs_note(exc)}", file=sys.stderr)
        return 1
    except (ValueError, TypeError, OSError, ImportError, GfinsError) as exc:
        print(f"gfins {args.command}: error: {exc}{_outputs_note(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        # every command writes its files as one set (gfins_fmi.io.output_set): an
        # interrupt leaves the previous set, or the new one when it came after the commit
        what = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
        print(f"gfins {args.command}: {what}{_outputs_note(exc)}", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
