"""The layers of DESIGN.md, held by parsing every import of both packages (function-level imports included).

* ``ppfab`` (the geometry core) imports only the standard library, numpy and scipy — never ``fabrication``,
  a CAD kernel, a file-format library or a plotting library;
* inside ``fabrication`` the layers run one way: components (beams, panels, nesting, …) → writers and
  verify → build → cli;
* no two modules import each other, directly or through others.

Imports under ``if TYPE_CHECKING:`` count for the layers too (an annotation that names a higher layer is a
dependency on it all the same); only the search for import cycles leaves them out, since they never run.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO

BLOCKED = ["build123d", "ezdxf", "matplotlib", "spyrrow", "rectpack", "fabrication", "OCP", "shapely", "trimesh",
           "ifcopenshell", "rhino3dm"]
STDLIB = set(sys.stdlib_module_names)
CORE_THIRD_PARTY = {"numpy", "scipy"}
# optional accelerators the core may load where it can do without them (arrays in, arrays out): MKL PARDISO for
# the optimiser's factorisations, SuperLU when it is missing (tests/test_linear_solvers.py)
CORE_OPTIONAL = {"ppfab.optimize.linsolve": {"pypardiso"}}
# fabrication's layers, lowest first; a module may import its own layer and the ones below
FAB_LAYERS = [
    {"model"},                      # the records of a finished build: data only, imports nothing of fabrication
    {"contract", "design", "flatpart", "beams", "panels", "nesting", "nodes", "figures",
     "htmlreport", "marking", "drawings", "node_sheets", "nodetypes", "examples", "starter", "glazing",
     "repetition", "erection", "erection_drawing", "surfacefile", "paper", "progress", "interrupts"},
    {"records", "parts", "glassorder", "report", "report_glazing"},   # the stages' records of one build, and what reads them whole
    {"writers", "verify", "readers"},
    {"pipeline"},
    {"cli", "studio", "sweep"},
]


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in ("ppfab", "fabrication"):
        for path in sorted((REPO / pkg).rglob("*.py")):
            rel = path.relative_to(REPO).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                for n in ast.walk(sub):
                    if hasattr(n, "lineno"):
                        lines.add(n.lineno)
    return lines


def _imports(module: str, annotations: bool = False) -> set[str]:
    """Absolute names of every module imported by ``module`` at run time (any depth in the file); with
    ``annotations`` also those imported under ``if TYPE_CHECKING:``."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = set() if annotations else _type_checking_lines(tree)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in MODULES else target)
    return found


IMPORTS = {m: _imports(m) for m in MODULES}
TYPED_IMPORTS = {m: _imports(m, annotations=True) for m in MODULES}


def _top(name: str) -> str:
    return name.split(".")[0]


def test_every_module_is_parsed():
    assert sum(m.startswith("ppfab") for m in MODULES) >= 40
    assert sum(m.startswith("fabrication") for m in MODULES) >= 40


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m.startswith("ppfab")))
def test_core_imports_only_numpy_scipy_and_itself(module):
    bad = sorted(name for name in TYPED_IMPORTS[module]
                 if _top(name) not in STDLIB | CORE_THIRD_PARTY | {"ppfab", "__future__", "_typeshed"}
                 | CORE_OPTIONAL.get(module, set()))
    assert bad == [], f"{module} imports {bad}"


def _layer(module: str) -> int:
    parts = module.split(".")
    if len(parts) == 1:
        return len(FAB_LAYERS) - 1                       # the package face: lazy API over every layer
    for k, names in enumerate(FAB_LAYERS):
        if parts[1] in names:
            return k
    raise AssertionError(f"{module} is in no layer of FAB_LAYERS: add it")


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m.startswith("fabrication")))
def test_fabrication_layers_run_one_way(module):
    mine = _layer(module)
    upward = sorted(name for name in TYPED_IMPORTS[module]
                    if _top(name) == "fabrication" and name in MODULES and _layer(name) > mine)
    assert upward == [], f"{module} (layer {mine}) imports higher layers: {upward}"


def test_no_import_cycles():
    graph = {m: sorted(n for n in IMPORTS[m] if n in MODULES and n != m) for m in MODULES}
    state: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in graph[m]:
            if state.get(n) == 1:
                cycles.append(stack[stack.index(n):] + [n])
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)
    assert cycles == []


def test_core_imports_with_fabrication_libraries_blocked():
    code = f"""
import sys, pkgutil, importlib
for name in {BLOCKED!r}:
    sys.modules[name] = None
import ppfab
mods = []
for info in pkgutil.walk_packages(ppfab.__path__, 'ppfab.'):
    importlib.import_module(info.name)
    mods.append(info.name)
from ppfab.constructions import load_all
load_all()
print(len(mods))
"""
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout.strip()) == sum(m.startswith("ppfab.") for m in MODULES)


def test_version_is_instant_and_light():
    code = "import sys; from fabrication.cli import main\n" \
           "try:\n    main(['--version'])\nexcept SystemExit:\n    pass\n" \
           "print(','.join(m for m in " + repr(BLOCKED[:-3]) + " if m in sys.modules and m != 'fabrication'))"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ppfab ")
    assert out.stdout.splitlines()[-1] == ""  # none of the heavy modules was imported
