"""A command's settings from a file (``--config FILE``), ``--print-config`` (a commented
template of it) and the effective configuration a run writes beside its outputs: one
mechanism for ``gfins integrate``, ``gfins align`` and ``gfins calibrate``.

A configuration file is TOML (``.toml``), YAML (``.yaml``/``.yml``) or the
``*.config.json`` a run wrote (its ``options``: the run repeated exactly). Its keys:

- the command's options by name (``lever_arm = "-0.3,0.2,1.2"`` or
  ``lever-arm = [-0.3, 0.2, 1.2]``, ``noise = "0.003,0.03m/s/sqrt(h),0.027,15mGal,1h"``,
  ``position = [34, 0, 80]``, ``smooth = true``, ``prior = ["gyro_bias_deg_h=0.05"]``, the
  files ``imu``, ``gnss``, ``output``, ...; align's ``mode``): each value goes through the
  option's own parser (units, bounds, messages), and an option given on the command line
  overrides it;
- ``gfins integrate`` only: ``[filter]``, any setting of the settings table
  (:mod:`gfins_fmi.estimation.settings`, the ``FilterConfig`` fields, SI units), checked
  by ``FilterConfig`` as in the API; ``[imu]`` / ``[noise]``, the noise block as ``gfins
  noise`` writes it (:mod:`gfins_fmi.estimation.noise_file`, read by its one reader), as
  ``--noise-file``;
- ``[inputs]``: the files (``imu``, ``gnss``, ``output``, ``truth``, ...), where TOML
  cannot hold both a key ``imu`` and a table ``[imu]``.

Paths in the file are relative to the file's folder (in a run's ``.config.json``: as they
were typed for that run).
"""
from __future__ import annotations

import argparse
import copy
import datetime
import json
import os
import pathlib
import sys

import yaml

from gfins_fmi._version import __version__
from gfins_fmi.estimation.noise_file import IMU_UNITS
from gfins_fmi.estimation.settings import python_settings

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.9 and 3.10 read TOML with tomli
    import tomli as tomllib

__all__ = ["apply_config", "config_template", "configured", "effective_config", "option_units",
           "config_beside", "input_file", "recording"]

#: option destinations that are files (relative to the configuration file)
_PATHS = ("imu", "gnss", "output", "baro", "odometer", "truth", "noise_file", "imu_errors", "plot", "kfgins_config")
#: what a configuration file does not set (nor a run records as an option)
_NOT_SET = ("config", "print_config", "command", "module", "function", "check", "given_options", "config_applied",
            "save_config", "resolved", "argv")
#: the commands whose files hold the filter's [filter] table and the noise block
_FILTER_COMMANDS = ("integrate",)


def _load(path: pathlib.Path) -> dict:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"--config {path}: cannot read it ({exc.strerror})") from None
    try:
        if path.suffix.lower() == ".json":
            # a run's OUT.config.json: its options as they were (paths as typed then)
            opts = dict(json.loads(text).get("options", {}))
            filt = opts.pop("filter_settings", None) or {}
            for k in ("given_options", "kfgins", "config", "save_config"):
                opts.pop(k, None)
            return dict(opts, _json=True, **({"filter": filt} if filt else {}))
        if path.suffix.lower() in (".yaml", ".yml"):
            doc = yaml.safe_load(text) or {}
        else:
            doc = tomllib.loads(text)
    except (ValueError, TypeError, yaml.YAMLError) as exc:
        raise ValueError(f"--config {path}: not a configuration file ({exc})") from None
    if not isinstance(doc, dict):
        raise ValueError(f"--config {path}: not a mapping of settings")
    return doc


def _text(value) -> str:
    """A file's value as the command line types it (a list: comma-separated)."""
    return ",".join(str(x) for x in value) if isinstance(value, (list, tuple)) else str(value)


def apply_config(parser: argparse.ArgumentParser, args, given: set, command: str = "integrate") -> None:
    """Fill ``args`` from ``args.config`` where the command line did not give the option
    (``given``: the destinations given on it). ``gfins integrate``: ``args.filter_settings``
    := its ``[filter]`` table; ``args.noise_file`` := the file itself when it holds a noise
    block and no other noise is given. Raises ValueError naming the key and what to change."""
    path = pathlib.Path(args.config)
    doc = _load(path)
    actions = {a.dest: a for a in parser._actions if a.dest not in ("help",)}   # argparse's own list
    with_filter = command in _FILTER_COMMANDS
    filter_settings = (doc.pop("filter", None) or {}) if with_filter else {}
    as_recorded = bool(doc.pop("_json", False))
    # the noise block's tables ([imu], [noise]) against the options imu (a file) and noise (a text)
    has_noise_block = with_filter and (isinstance(doc.get("imu"), dict) or isinstance(doc.get("noise"), dict))
    for table in ("imu", "noise"):
        if with_filter and isinstance(doc.get(table), dict):
            doc.pop(table)
    inputs = doc.pop("inputs", None) or {}
    if not isinstance(inputs, dict):
        raise ValueError(f"--config {path}: [inputs] must be a table of files (imu, gnss, output, truth, ...)")
    doc.update(inputs)       # TOML cannot hold a key imu and a table [imu]: the files may go in [inputs]
    for key, value in doc.items():
        dest = key.replace("-", "_")
        if dest in _NOT_SET or dest in given or value is None:
            continue
        if dest not in actions:
            raise ValueError(f"--config {path}: unknown setting {key!r}; the options of gfins {command} "
                             f"(gfins {command} --print-config lists them)")
        if isinstance(value, dict):
            raise ValueError(f"--config {path}: {key} must be a value, not a table")
        action = actions[dest]
        if action.nargs == 0:      # a flag
            if not isinstance(value, bool):
                raise ValueError(f"--config {path}: {key} must be true or false; got {value!r}")
            setattr(args, dest, value)
            continue
        if isinstance(action, argparse._AppendAction):   # argparse's class of a repeatable option
            items = value if isinstance(value, (list, tuple)) else [value]
            try:
                setattr(args, dest, [action.type(_text(x)) if action.type else _text(x) for x in items])
            except argparse.ArgumentTypeError as exc:
                raise ValueError(f"--config {path}: {key}: {exc}") from None
            continue
        text = _text(value)
        if dest in _PATHS or action.type is pathlib.Path:
            p = pathlib.Path(text)
            setattr(args, dest, p if p.is_absolute() or as_recorded else path.parent / p)
            continue
        if action.choices is not None and text not in [str(c) for c in action.choices]:
            raise ValueError(f"--config {path}: {key} must be one of {', '.join(map(str, action.choices))}; "
                             f"got {text!r}")
        try:
            setattr(args, dest, action.type(text) if action.type else text)
        except argparse.ArgumentTypeError as exc:
            raise ValueError(f"--config {path}: {key}: {exc}") from None
    if not with_filter:
        return
    if not isinstance(filter_settings, dict):
        raise ValueError(f"--config {path}: [filter] must be a table of settings")
    known = {s.python_name for s in python_settings()} - {"imu", "input"}
    unknown = sorted(set(filter_settings) - known)
    if unknown:
        raise ValueError(f"--config {path}: [filter] {', '.join(unknown)}: not a filter setting; the settings are "
                         f"{', '.join(sorted(known))} (gfins integrate --print-config)")
    args.filter_settings = dict(filter_settings)
    if has_noise_block and "noise" not in given and "noise_file" not in given and args.noise is None:
        args.noise_file = path


def _typed(parser: argparse.ArgumentParser, tokens: list) -> set:
    """The destinations the command line set (``tokens``: what was typed after the
    command's name), whatever their values: the command's parser again, every default
    suppressed (so an option typed with its default value counts as given)."""
    quiet = copy.deepcopy(parser)
    for a in quiet._actions:   # argparse's own list of the options
        # a positional stays None when absent (a suppressed default would meet its choices)
        a.default = argparse.SUPPRESS if a.option_strings else None
        a.required = False
    try:
        ns, _ = quiet.parse_known_args(tokens)
    except SystemExit:         # pragma: no cover - the same tokens were parsed once already
        return set()
    return {k for k, v in vars(ns).items() if v is not None}


def configured(args, parser: argparse.ArgumentParser, command: str, check=None) -> None:
    """``--config``: the file's values where the command line gave none, then ``check``
    (the command's parse-time check of option combinations) on the result;
    ``args.given_options`` := the options given on the command line (typed, from
    ``args.argv``; without it, those whose value differs from the default). Raises
    ValueError with the check's message."""
    defaults = {a.dest: a.default for a in parser._actions}   # argparse's own list of the options
    tokens = getattr(args, "argv", None)
    name = command.split()[0]
    if tokens is not None and name in tokens:
        typed = _typed(parser, tokens[tokens.index(name) + 1:])
        args.given_options = sorted(k for k in typed if k in defaults and k not in _NOT_SET)
    else:
        args.given_options = sorted(k for k, v in vars(args).items() if k in defaults and v != defaults[k])
    args.filter_settings = {}
    if args.config is None:
        return
    apply_config(parser, args, set(args.given_options), command)
    args.config_applied = True
    problem = check(args) if check else None
    if problem:
        raise ValueError(problem)


def input_file(path) -> dict | None:
    """An input file as a run records it: path, size, modification time (UTC)."""
    if not path or not os.path.isfile(path):
        return None
    st = os.stat(path)
    return {"path": str(path), "bytes": st.st_size,
            "modified_utc": datetime.datetime.fromtimestamp(st.st_mtime, datetime.timezone.utc).isoformat()}


def _recorded(value):
    if isinstance(value, pathlib.Path):
        return str(value)
    if isinstance(value, (list, tuple)):
        # a repeatable NAME=VALUE option (--prior) as it is typed
        if value and all(isinstance(x, tuple) and len(x) == 2 and isinstance(x[0], str) for x in value):
            return [f"{k}={v!r}" for k, v in value]
        return [_recorded(x) for x in value]
    return value


def option_units(parser: argparse.ArgumentParser) -> dict:
    """The unit of every option that has one (its type's ``.unit``), by destination."""
    units = {}
    for a in parser._actions:   # argparse's own list of the options
        unit = getattr(a.type, "unit", None)
        if unit and a.dest not in _NOT_SET:
            units[a.dest] = unit
    return units


def effective_config(parser: argparse.ArgumentParser, args, command: str, inputs=(), resolved=None) -> str:
    """What a run used, as JSON, to read back or repeat it (``--config`` of this file):
    every option with its value (defaults filled in), their units (the option types'
    ``.unit``), the input files (path, size, time), and ``resolved``: the values the run
    chose itself (the grade's defaults, a window), each named with its unit."""
    options = {a.dest: _recorded(getattr(args, a.dest, a.default)) for a in parser._actions   # argparse's list
               if a.dest not in ("help", *_NOT_SET)}
    units = option_units(parser)
    doc = {"gfins_fmi": __version__, "command": command,
           "repeat": f"gfins {command.split()[0]} --config THIS_FILE (options given on the command line override it)",
           "inputs": {str(p): input_file(p) for p in inputs if p},
           "options": options, "units": units, "resolved": resolved or {}}
    return json.dumps(doc, indent=1, default=float) + "\n"


def config_beside(args, files=(), folder=None, command: str = "run"):
    """Where a run's effective configuration goes: ``--save-config FILE`` if given, else
    beside the first of the run's output ``files`` (``OUT.config.json``), else in its
    output ``folder`` (``FOLDER/<command>.config.json``); None for a run that writes no
    file."""
    saved = getattr(args, "save_config", None)
    if saved:
        return pathlib.Path(saved)
    first = next((pathlib.Path(f) for f in files if f), None)
    if first is not None:
        return first.with_suffix(".config.json")
    return pathlib.Path(folder) / f"{command}.config.json" if folder else None


def config_template(parser: argparse.ArgumentParser, command: str = "integrate") -> str:
    """A commented TOML template: every option of ``gfins COMMAND`` with its help (units,
    default); for ``gfins integrate`` also the [filter] table from the settings table and
    the noise block's keys."""
    out = [f"# gfins {command} --config FILE.toml: every setting of a run. Options given on the",
           "# command line override this file; paths are relative to its folder. Uncomment to set.", ""]
    for a in parser._actions:   # argparse's own list of the options
        if a.dest in ("help", *_NOT_SET):
            continue
        helptext = " ".join((a.help or "").split()).replace("%%", "%")
        unit = getattr(a.type, "unit", None)
        if a.choices is not None and not isinstance(a.choices, range):
            helptext += f" [one of: {', '.join(map(str, a.choices))}]"
        elif unit and unit != "count":
            helptext += f" [{unit}]"
        out.append(f"# {helptext}")
        default = a.default
        if isinstance(default, (list, tuple)):
            default = "[" + ", ".join(str(x) for x in default) + "]" if default else None
        elif isinstance(default, (str, pathlib.Path)):
            default = f'"{default}"'
        value = ("true" if a.default else "false") if a.nargs == 0 else (
            default if default is not None else "  (not set by default)")
        if isinstance(a, argparse._AppendAction):   # argparse's class of a repeatable option
            value = '["NAME=VALUE", ...]'
        out.append(f"# {a.dest} = {value}")
        out.append("")
    if command not in _FILTER_COMMANDS:
        return "\n".join(out)
    out += ["[filter]", "# the filter's settings (gfins_fmi/estimation/settings.py), SI units; FilterConfig checks them"]
    for s in python_settings():
        if s.python_name in ("imu", "input"):
            continue
        unit = f" [{s.unit}]" if s.unit else ""
        out.append(f"# {s.meaning}{unit}")
        d = s.default
        shown = ("true" if d else "false") if isinstance(d, bool) else (
            f'"{d}"' if isinstance(d, str) else ("[" + ", ".join(map(str, d)) + "]" if isinstance(d, tuple) else d))
        out.append(f"# {s.python_name} = {shown}" if d is not None else f"# {s.python_name} =   (none by default)")
    out += ["", "[imu]", "# the IMU's noise (the noise block of gfins noise; or give noise = \"...\" above)"]
    for k, what in IMU_UNITS.items():
        out.append(f"# {k} = 0.0   # {what}")
    return "\n".join(out) + "\n"


def recording(run, parser: argparse.ArgumentParser, command: str, path, inputs=()):
    """``run(args, outs)`` (a command's body inside its output set) that then writes the
    effective configuration to ``path`` (None: not written) through the same set: it
    appears with the run's other outputs, or not at all. ``args.resolved``: the values
    the run chose itself, recorded with it."""
    def go(args, outs) -> int:
        status = run(args, outs)
        if path is not None:
            outs.write_text(path, effective_config(parser, args, command, inputs, getattr(args, "resolved", None)))
        return status
    return go
