"""Source audits of the Python package (gfins_fmi/): the shape of the domain map, read from
the sources (nothing is imported).

* imports point one way: ``cli``, ``experiments`` -> ``fmi``, ``analysis`` ->
  ``estimation``, ``calibration`` -> ``nav``, ``gyrofree``, ``sim`` -> ``_lib``, ``io``
  (a total order of the packages, :data:`LAYERS`: a module imports modules of its own
  package or of packages below it, never the package root's re-exports);
* no module imports another module's private name (``from x import _y``, ``x._y``),
  and a private module (``io/_text.py``) is imported only inside its package; the C
  extension only by ``_lib``;
* imports at the top of the module, but for the heavy or optional third-party modules of
  :data:`LAZY` (each import site says why in a ``# lazy:`` comment) and the one dynamic
  import of :data:`DYNAMIC`;
* no module over :data:`MAX_LINES` lines but those of :data:`LONG` (each with its reason);
* no import cycles;
* ``nav/earth.py`` imports nothing but numpy (the tests take it as truth: it must not
  depend on the C core it checks).
"""
from __future__ import annotations

import ast
import pathlib

from support.paths import ROOT

PACKAGE = ROOT / "gfins_fmi"

#: the packages (and top-level modules) from the top of the import order to its bottom: a
#: module may import its own package's modules and those of later entries (``io`` and
#: ``_lib``, the door to the C extension ``_core``, form the bottom; ``_version`` holds
#: the version alone)
LAYERS = ("cli", "experiments", "fmi", "analysis", "calibration", "estimation", "sim",
          "gyrofree", "nav", "io", "_lib", "_core", "_version")

#: third-party modules imported inside the functions that need them, not at the top: each
#: costs start-up time that every command would pay (CPU time of the import alone, numpy
#: loaded, measured on the development machine; `import gfins_fmi.cli`, all that
#: `gfins --help` loads, takes ~71 ms, numpy's 52 of them), or is an optional extra
LAZY = {
    "control": "python-control: ~810 ms",
    "scipy": "scipy.signal ~510 ms, scipy.stats ~450 ms, scipy.spatial.transform ~170 ms, "
             "scipy.linalg ~100 ms",
    "matplotlib": "matplotlib.pyplot: ~270 ms, figures only",
    "polars": "polars: ~100 ms, CSV tables only",
    "fmpy": "fmpy: ~30 ms, where an FMU runs",
    "tqdm": "tqdm: ~25 ms, progress bars only",
    "pyarrow": "optional extra gfins_fmi[parquet] (pyarrow.parquet ~40 ms)",
    "distributed": "optional extra gfins_fmi[dask] (~200 ms)",
    "libcosimpy": "optional extra gfins_fmi[osp]",
}

#: imports made by name at run time: module -> why. ``gfins`` imports only the command it
#: runs: with every command module imported, `import gfins_fmi.cli` takes ~112 ms instead
#: of ~71 ms (measured as above), i.e. `gfins --help` would be ~1.6x slower
DYNAMIC = {"gfins_fmi.cli": "main() imports gfins_fmi.cli.<command> of the chosen command",
           "gfins_fmi": "the root's re-exports, imported when first used (PEP 562 __getattr__: a "
                        "command's start does not load what it does not use)"}

MAX_LINES = 600
#: modules longer than MAX_LINES, and why they read better whole
LONG = {
    "gfins_fmi.io.records": "the five record types (IMU, GNSS, barometer, odometer, truth) on one "
                            "base class and its validation helpers, which every record shares",
}


def _modules() -> dict[str, pathlib.Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


MODULES = _modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8")) for name, path in MODULES.items()}


def _package(module: str) -> str:
    """``gfins_fmi.nav.earth`` -> ``nav``; ``gfins_fmi._lib`` -> ``_lib``; the root -> ''."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _layer(package: str) -> int:
    for k, entry in enumerate(LAYERS):
        if package == entry or (isinstance(entry, tuple) and package in entry):
            return k
    raise AssertionError(f"package {package!r} is not in LAYERS: add it where it belongs")


def _imports(name: str):
    """(line, imported module, imported names, inside a function) of a module's imports of
    gfins_fmi; ``from pkg import sub`` of a submodule counts as an import of ``pkg.sub``."""
    tree, is_pkg = TREES[name], MODULES[name].name == "__init__.py"
    base = name if is_pkg else name.rpartition(".")[0]

    def walk(node, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import):
                for alias in child.names:
                    if alias.name.split(".")[0] == "gfins_fmi":
                        yield child.lineno, alias.name, (), in_function
            elif isinstance(child, ast.ImportFrom):
                mod = child.module or ""
                if child.level:
                    parts = base.split(".")
                    mod = ".".join(parts[:len(parts) - child.level + 1] + ([mod] if mod else []))
                if mod.split(".")[0] == "gfins_fmi":
                    subs = [a.name for a in child.names if f"{mod}.{a.name}" in MODULES]
                    names = [a.name for a in child.names if f"{mod}.{a.name}" not in MODULES]
                    for s in subs:
                        yield child.lineno, f"{mod}.{s}", (), in_function
                    if names:
                        yield child.lineno, mod, tuple(names), in_function
            yield from walk(child, in_function or isinstance(
                child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))
    yield from walk(tree, False)


def test_the_map_is_known():
    """Every package of gfins_fmi/ is in LAYERS (a new one must be placed on purpose)."""
    for name in MODULES:
        if name != "gfins_fmi":
            _layer(_package(name))


def test_imports_point_one_way():
    offenders = []
    for name in MODULES:
        if name == "gfins_fmi":      # the package root re-exports the public names
            continue
        own = _package(name)
        for line, target, names, _ in _imports(name):
            if target == "gfins_fmi":
                offenders.append(f"{name}:{line}: imports the package root's re-exports {names}")
                continue
            other = _package(target)
            if other != own and _layer(other) <= _layer(own):
                offenders.append(f"{name}:{line}: imports {target} ({own} -> {other} points upward "
                                 "or sideways)")
    assert not offenders, "imports against the direction of the map:\n" + "\n".join(offenders)


def test_no_module_imports_another_modules_private_names():
    offenders = []
    for name, tree in TREES.items():
        bound = {}      # local name -> the gfins_fmi module it is bound to
        for line, target, names, _ in _imports(name):
            for n in names:
                if n.startswith("_") and not n.startswith("__") and f"{target}.{n}" not in MODULES:
                    offenders.append(f"{name}:{line}: from {target} import {n}")
            leaf = target.rpartition(".")[2]
            if leaf.startswith("_") and target not in ("gfins_fmi._lib", "gfins_fmi._version"):
                inside = target.rpartition(".")[0]
                if target == "gfins_fmi._core" and name != "gfins_fmi._lib":
                    offenders.append(f"{name}:{line}: imports the C extension (only _lib does)")
                elif target != "gfins_fmi._core" and not (name + ".").startswith(inside + "."):
                    offenders.append(f"{name}:{line}: imports {target}, private to {inside}")
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("gfins_fmi"):
                for a in node.names:
                    if f"{node.module}.{a.name}" in MODULES:
                        bound[a.asname or a.name] = f"{node.module}.{a.name}"
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.startswith("gfins_fmi") and a.asname:
                        bound[a.asname] = a.name
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in bound and node.attr.startswith("_")
                    and not node.attr.startswith("__")):
                offenders.append(f"{name}:{node.lineno}: {node.value.id}.{node.attr} "
                                 f"({bound[node.value.id]})")
    assert not offenders, "private names used across modules:\n" + "\n".join(offenders)


def test_imports_are_at_the_top():
    """An import inside a function is of a LAZY third-party module, with a ``# lazy:``
    comment at it or earlier in the function; gfins_fmi modules are imported at the top
    (run-time imports by name: DYNAMIC only)."""
    offenders = []
    for name, tree in TREES.items():
        lines = MODULES[name].read_text(encoding="utf-8").split("\n")

        def visit(node, func):
            for child in ast.iter_child_nodes(node):
                f = child if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else func
                if func is not None and isinstance(child, (ast.Import, ast.ImportFrom)):
                    mods = ([child.module or ""] if isinstance(child, ast.ImportFrom)
                            else [a.name for a in child.names])
                    for mod in mods:
                        top = mod.split(".")[0]
                        if getattr(child, "level", 0) or top == "gfins_fmi":
                            offenders.append(f"{name}:{child.lineno}: {mod} imported in a function")
                        elif top not in LAZY:
                            offenders.append(f"{name}:{child.lineno}: {mod} imported in a function "
                                             "(not a LAZY module: import it at the top)")
                        elif not any("# lazy:" in ln for ln in lines[func.lineno - 1:child.lineno]):
                            offenders.append(f"{name}:{child.lineno}: lazy import of {mod} without a "
                                             "'# lazy:' comment saying why")
                visit(child, f)
        visit(tree, None)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "import_module" and name not in DYNAMIC):
                offenders.append(f"{name}:{node.lineno}: importlib.import_module (not in DYNAMIC)")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "__import__":
                offenders.append(f"{name}:{node.lineno}: __import__")
    assert not offenders, "\n".join(offenders)


def test_modules_are_short():
    long = {name: n for name, path in MODULES.items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    unexplained = {k: v for k, v in long.items() if k not in LONG}
    assert not unexplained, (f"modules over {MAX_LINES} lines (split them at their seams, or say in "
                             f"LONG why they read better whole): {unexplained}")
    stale = sorted(set(LONG) - set(long))
    assert not stale, f"LONG lists modules that are no longer long: {stale}"


def test_no_import_cycles():
    graph = {name: sorted({t for _, t, _, _ in _imports(name) if t in MODULES and t != name})
             for name in MODULES}
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def strongconnect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                strongconnect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in graph:
        if v not in index:
            strongconnect(v)
    assert not cycles, f"import cycles: {cycles}"


def test_earth_model_is_independent_of_the_c_core():
    tree = TREES["gfins_fmi.nav.earth"]
    imported = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {(n.module or "").split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert imported <= {"numpy", "__future__"}, f"nav/earth.py imports {imported - {'numpy', '__future__'}}"
