"""The Python examples of the README and of docs/*.md run as written (so the docs stay
true)."""
from __future__ import annotations

import re

import pytest

from support.paths import ROOT

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = [(doc.name, i, block) for doc in DOCS
          for i, block in enumerate(re.findall(r"```python\n(.*?)```", doc.read_text(encoding="utf-8"), re.S))]


def test_readme_has_examples():
    assert sum(1 for name, _, _ in BLOCKS if name == "README.md") >= 3


@pytest.mark.parametrize("name, index, block", BLOCKS, ids=[f"{n}-{i + 1}" for n, i, _ in BLOCKS])
def test_doc_example_runs(name, index, block, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)   # files an example writes (figures) stay out of the checkout
    exec(compile(block, f"{name} python block {index + 1}", "exec"), {})
