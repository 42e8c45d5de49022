"""The parser names what it does not import (so that ``gfins --help`` stays light): its
choices agree with the modules that own them."""
from __future__ import annotations

import importlib

from gfins_fmi.analysis.error_report import CONFIGS
from gfins_fmi.cli.options import GRADES
from gfins_fmi.cli.parser import ANALYZE_CONFIGS, build_parser
from gfins_fmi.sim.scenarios import GRADES as NOISE_MODELS


def test_parser_choices_are_the_owners():
    assert ANALYZE_CONFIGS == CONFIGS
    assert GRADES == tuple(NOISE_MODELS)


def test_every_command_names_a_module_that_runs_it():
    _, parsers = build_parser()
    for name, p in parsers.items():
        module = importlib.import_module(f"gfins_fmi.cli.{p.get_default('module')}")
        assert callable(getattr(module, p.get_default("function"))), name
