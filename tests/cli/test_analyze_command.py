"""``gfins analyze``: the report and its figures written.
"""
from __future__ import annotations

import pytest


def test_analyze_command_writes_the_report(tmp_path):
    """gfins analyze: a markdown report with a table and a figure per configuration."""
    from gfins_fmi.cli import main
    assert main(["analyze", "--config", "qin9", "--runs", "20", "--out", str(tmp_path), "--quiet"]) == 0
    text = (tmp_path / "report.md").read_text()
    assert "## qin9" in text and "error_growth_qin9.png" in text
    assert (tmp_path / "error_growth_qin9.png").stat().st_size > 10_000
    with pytest.raises(SystemExit) as exc:     # refused when parsed (a std needs 2 runs)
        main(["analyze", "--config", "qin9", "--runs", "1", "--out", str(tmp_path)])
    assert exc.value.code == 2
