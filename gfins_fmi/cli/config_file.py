"""``gfins integrate --config FILE``: the run's settings from a file, and ``--print-config``,
a commented template of it.

A configuration file is TOML (``.toml``), YAML (``.yaml``/``.yml``) or the
``OUT.config.json`` a run wrote (its ``options``: the run repeated exactly). Its keys:

- the options of ``gfins integrate`` by name (``lever_arm = "-0.3,0.2,1.2"`` or
  ``lever-arm = [-0.3, 0.2, 1.2]``, ``noise = "0.003,0.03m/s/sqrt(h),0.027,15mGal,1h"``,
  ``initial``, ``position_std``, ``outages``, ``smooth = true``, the files ``imu``,
  ``gnss``, ``output``, ...): each value goes through the option's own parser (units,
  bounds, messages), and an option given on the command line overrides it;
- ``[filter]``: any setting of the settings table
  (:mod:`gfins_fmi.estimation.settings`, the ``FilterConfig`` fields, SI units), checked
  by ``FilterConfig`` as in the API;
- ``[imu]`` / ``[noise]``: the noise block as ``gfins noise`` writes it
  (:mod:`gfins_fmi.estimation.noise_file`, read by its one reader), as ``--noise-file``;
  TOML cannot hold both a key ``imu`` and a table ``[imu]``: the files may then go in an
  ``[inputs]`` table (``imu``, ``gnss``, ``output``, ``truth``, ...).

Paths in the file are relative to the file's folder.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import yaml

from gfins_fmi.estimation.noise_file import IMU_UNITS
from gfins_fmi.estimation.settings import python_settings

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.9 and 3.10 read TOML with tomli
    import tomli as tomllib

__all__ = ["apply_config", "config_template"]

#: option destinations that are files (relative to the configuration file)
_PATHS = ("imu", "gnss", "output", "baro", "odometer", "truth", "noise_file", "imu_errors", "plot", "kfgins_config")
#: what a configuration file does not set
_NOT_SET = ("config", "print_config", "command", "module", "function", "check", "given_options")


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
            for k in ("given_options", "kfgins", "config"):
                opts.pop(k, None)
            return dict(opts, filter=filt, _json=True)
        if path.suffix.lower() in (".yaml", ".yml"):
            doc = yaml.safe_load(text) or {}
        else:
            doc = tomllib.loads(text)
    except (ValueError, TypeError, yaml.YAMLError) as exc:
        raise ValueError(f"--config {path}: not a configuration file ({exc})") from None
    if not isinstance(doc, dict):
        raise ValueError(f"--config {path}: not a mapping of settings")
    return doc


def apply_config(parser: argparse.ArgumentParser, args, given: set) -> None:
    """Fill ``args`` from ``args.config`` where the command line did not give the option
    (``given``: the destinations given on it); ``args.filter_settings`` := its
    ``[filter]`` table; ``args.noise_file`` := the file itself when it holds a noise
    block and no other noise is given."""
    path = pathlib.Path(args.config)
    doc = _load(path)
    actions = {a.dest: a for a in parser._actions if a.dest not in ("help",)}   # argparse's own list
    filter_settings = doc.pop("filter", None) or {}
    as_recorded = bool(doc.pop("_json", False))
    # the noise block's tables ([imu], [noise]) against the options imu (a file) and noise (a text)
    has_noise_block = isinstance(doc.get("imu"), dict) or isinstance(doc.get("noise"), dict)
    for table in ("imu", "noise"):
        if isinstance(doc.get(table), dict):
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
            raise ValueError(f"--config {path}: unknown setting {key!r}; the options of gfins integrate "
                             f"(gfins integrate --print-config lists them)")
        action = actions[dest]
        if action.nargs == 0:      # a flag
            if not isinstance(value, bool):
                raise ValueError(f"--config {path}: {key} must be true or false; got {value!r}")
            setattr(args, dest, value)
            continue
        text = ",".join(str(x) for x in value) if isinstance(value, (list, tuple)) else str(value)
        if dest in _PATHS:
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


def config_template(parser: argparse.ArgumentParser) -> str:
    """A commented TOML template: every option of ``gfins integrate`` with its help (units,
    default), the [filter] table from the settings table, the noise block's keys."""
    out = ["# gfins integrate --config FILE.toml: every setting of a run. Options given on the",
           "# command line override this file; paths are relative to its folder. Uncomment to set.", ""]
    for a in parser._actions:   # argparse's own list of the options
        if a.dest in ("help", *_NOT_SET) or not a.option_strings and a.dest not in ("imu", "gnss", "output"):
            continue
        helptext = " ".join((a.help or "").split())
        out.append(f"# {helptext}")
        default = a.default
        if isinstance(default, (list, tuple)):
            default = ",".join(str(x) for x in default)
        value = "false" if a.nargs == 0 else (f'"{default}"' if default is not None else '""')
        out.append(f"# {a.dest} = {value}")
        out.append("")
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
