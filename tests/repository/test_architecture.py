"""docs/architecture.md matches the tree: every module of csrc/, gfins_fmi/ and fmu/ is
named on the page, and every file the page names exists (a move or a new module that
forgets the map fails here)."""
from __future__ import annotations

import re

from support.paths import ROOT

PAGE = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")


def _named(rel: str) -> bool:
    """`rel` (a path below csrc/, gfins_fmi/ or fmu/) on the page, alone or as x.{h,c}."""
    stem, _, ext = rel.rpartition(".")
    return rel in PAGE or f"{stem}.{{h,c}}" in PAGE


def test_every_c_file_is_on_the_page():
    missing = [str(p.relative_to(ROOT / "csrc")) for p in sorted((ROOT / "csrc").rglob("*"))
               if p.suffix in (".c", ".h", ".py") and not _named(str(p.relative_to(ROOT / "csrc")))]
    assert not missing, f"csrc files not in docs/architecture.md: {missing}"


def test_every_python_module_is_on_the_page():
    pkg = ROOT / "gfins_fmi"
    missing = []
    for p in sorted(pkg.rglob("*.py")):
        rel = str(p.relative_to(pkg))
        if p.name == "__init__.py" and p.parent != pkg and p.parent.name != "cli":
            continue          # a subpackage's __init__: its modules are listed
        if not _named(rel):
            missing.append(rel)
    assert not missing, f"gfins_fmi modules not in docs/architecture.md: {missing}"


def test_every_fmu_source_and_model_is_on_the_page():
    missing = [p.name for p in sorted((ROOT / "fmu" / "glue").iterdir()) if p.name not in PAGE]
    missing += [f"fmu/tools/{p.name}" for p in sorted((ROOT / "fmu" / "tools").glob("*.py"))
                if f"fmu/tools/{p.name}" not in PAGE]
    models = [p.name for p in sorted((ROOT / "fmu" / "models").iterdir()) if p.is_dir()]
    missing += [m for m in models if f"`{m}`" not in PAGE and f"/{m}/" not in PAGE
                and f"`{m}/`" not in PAGE]
    assert not missing, f"fmu sources and models not in docs/architecture.md: {missing}"


def test_every_file_the_page_names_exists():
    """Backquoted paths with a folder and a source suffix must exist (x.{h,c}: both)."""
    bases = [ROOT, ROOT / "csrc", ROOT / "gfins_fmi"]
    stale = []
    for token in re.findall(r"`([A-Za-z0-9_./{},]+\.(?:py|c|h|\{h,c\}))`", PAGE):
        if "/" not in token or "<" in token or "*" in token:
            continue
        names = [token.replace("{h,c}", "h"), token.replace("{h,c}", "c")] if "{h,c}" in token else [token]
        for name in names:
            if not any((b / name).exists() for b in bases):
                stale.append(name)
    assert not stale, f"docs/architecture.md names files that do not exist: {stale}"


def test_every_file_named_in_references_and_contributing_exists():
    stale = []
    for page in ("references.md", "contributing.md"):
        text = (ROOT / "docs" / page).read_text(encoding="utf-8")
        for token in re.findall(r"`([A-Za-z0-9_./]+\.(?:py|c|h|md))(?:::\w+)?`", text):
            if "/" in token and not any((b / token).exists() for b in (ROOT, ROOT / "docs")):
                stale.append(f"{page}: {token}")
    assert not stale, stale
