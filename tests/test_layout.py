"""The package layout (issue 16): subpackages in pipeline order, each importing only from its own stage and earlier
ones (eagerly or inside functions), and no import circles. Parsed with ast, nothing is imported.

relayout: skip (this file names the packages themselves)
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "robotdyn"

# pipeline order: a module of stage i may import from stages <= i only
STAGES = [
    ("foundation", ["errors", "inputs", "input_files", "output", "_lazy"]),
    ("description", ["description"]),
    ("constraints", ["constraints"]),
    ("reduction", ["reduction"]),
    ("fast", ["fast", "_compiled"]),
    ("contact", ["contact"]),
    ("robot", ["robot"]),
    ("simulation", ["simulation"]),
    ("optimisation", ["optimisation"]),
    ("interfaces", ["interfaces"]),
    ("robots", ["robots", ""]),  # "": the package's own __init__ (robotdyn.load builds a registered robot)
    ("sweep", ["sweep"]),
    ("cli", ["cli", "__main__"]),
]
STAGE = {top: i for i, (_, tops) in enumerate(STAGES) for top in tops}

# known exceptions, each an import inside a function: (importing module, imported module)
UPWARD = {
    # the robot modules register their own subcommands (and print with the CLI's helpers)
    ("robots.adaptable_wheel.comparison", "cli.commands"),
    ("robots.linkage_suspension.model", "cli.commands"),
    ("robots.mmr12_eod.model", "cli.fk"),
    ("robots.mmr12_eod.climbing_posture", "cli.commands"),
    ("robots.omni_caster.model", "cli.commands"),
    # simulate_many(robot="quasimoro"): a robot given by its registered name
    ("simulation.many_runs", ""),
}
# circles through imports inside functions, within one stage (a module-level circle is never allowed)
LAZY_CIRCLES = {
    frozenset({"simulation.engine", "simulation.streaming"}),  # simulate(sink=) <-> its segments' simulate calls
    frozenset({"cli.commands", "cli.sweep"}),  # the sweep subcommand registers itself, and prints with _emit
    frozenset({"cli.commands", "cli.fk"}),
    frozenset({"cli.commands", "cli.linearize"}),  # the linearize subcommand registers itself, prints with _emit
    frozenset({"cli.commands", "cli.optimise"}),  # the optimise subcommand likewise
    frozenset({"sweep.chunk", "sweep.batched"}),
    frozenset({"contact.sliding", "contact.sliding_rigid_limit"}),  # forward <-> its coupled solve on open loads
    # MMR12-EOD's CLI hook (model) registers the climbing-posture command, which builds on the model's climbing robot
    frozenset({"robots.mmr12_eod.model", "robots.mmr12_eod.climbing_posture"}),  # a chunk's batched runs; the batch reuses the per-run summary
    # the adaptable wheel's hold scenario (model) starts from the paper's IK placement (comparison, missions)
    frozenset({"robots.adaptable_wheel.model", "robots.adaptable_wheel.comparison", "robots.adaptable_wheel.missions"}),
}


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted(PKG.rglob("*.py")):
        parts = list(p.relative_to(PKG).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()
MODULES["_compiled"] = PKG / "_compiled.cpp"  # the C++ extension (robotdyn/_compiled.cpp, built by setup.py)


def _resolve(name: str) -> str:
    """The module an import names (a name imported from a package, if not a module, stands for the package)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _imports(mod: str, path: Path) -> list[tuple[str, bool, int]]:
    """(imported robotdyn module, at module level, line) for every import of ``mod``."""
    if path.suffix != ".py":
        return []
    tree = ast.parse(path.read_text())
    pkg = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    module_level = set()
    for node in tree.body:  # module level, including under `if`/`try` at module level (not TYPE_CHECKING)
        stack = [node]
        while stack:
            n = stack.pop()
            if isinstance(n, ast.If) and "TYPE_CHECKING" in ast.unparse(n.test):
                continue
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            module_level.add(id(n))
            stack.extend(ast.iter_child_nodes(n))
    out = []
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".") if pkg else []
                base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
                absmod = ".".join([*base, *([node.module] if node.module else [])])
            elif node.module and (node.module == "robotdyn" or node.module.startswith("robotdyn.")):
                absmod = node.module[len("robotdyn."):] if node.module != "robotdyn" else ""
            else:
                continue
            for a in node.names:
                sub = f"{absmod}.{a.name}" if absmod else a.name
                targets.append(sub if sub in MODULES else _resolve(absmod))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "robotdyn" or a.name.startswith("robotdyn."):
                    targets.append(_resolve(a.name[len("robotdyn."):] if a.name != "robotdyn" else ""))
        for t in targets:
            if t != mod:
                out.append((t, id(node) in module_level, node.lineno))
    return out


GRAPH = {m: _imports(m, p) for m, p in MODULES.items()}


def _stage(mod: str) -> int:
    return STAGE[mod.split(".")[0]]


def test_every_module_has_a_stage():
    assert [m for m in MODULES if m.split(".")[0] not in STAGE] == []


def test_subpackages_say_what_they_own_and_may_import():
    for name, _ in STAGES:
        init = PKG / name / "__init__.py"
        if init.exists() and name != "robots":
            doc = ast.get_docstring(ast.parse(init.read_text())) or ""
            assert "Owns" in doc and "Import" in doc, f"robotdyn/{name}/__init__.py: say what it owns and imports"


def test_no_upward_imports():
    bad = []
    for mod, imports in GRAPH.items():
        for target, _, line in imports:
            if _stage(target) > _stage(mod) and (mod, target) not in UPWARD:
                bad.append(f"robotdyn/{MODULES[mod].relative_to(PKG)}:{line}: {mod or 'robotdyn'} "
                           f"({STAGES[_stage(mod)][0]}) imports {target or 'robotdyn'} ({STAGES[_stage(target)][0]})")
    assert bad == [], "imports against the pipeline order:\n" + "\n".join(bad)


def test_exceptions_are_still_needed():
    """An exception that no longer happens is removed from the list, so that it cannot come back unnoticed."""
    used = {(m, t) for m, imports in GRAPH.items() for t, _, _ in imports}
    assert UPWARD - used == set()


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in list(edges):
        if v not in index:
            visit(v)
    return out


def test_no_circles_at_module_level():
    edges = {m: {t for t, eager, _ in imports if eager} for m, imports in GRAPH.items()}
    assert _cycles(edges) == []


def test_no_circles_but_the_known_lazy_ones():
    edges = {m: {t for t, _, _ in imports if (m, t) not in UPWARD and not any({m, t} <= c for c in LAZY_CIRCLES)}
             for m, imports in GRAPH.items()}
    assert _cycles(edges) == []


@pytest.mark.parametrize("pair", sorted(tuple(sorted(c)) for c in LAZY_CIRCLES))
def test_known_lazy_circles_are_within_one_stage(pair):
    assert len({_stage(m) for m in pair}) == 1


def test_compiled_kernels_name_their_python_twins():
    """Each C++ kernel under robotdyn/kernels/ (issue 26, item 5) opens with a comment naming its Python reference,
    whose module has the kernel's name (rolling_contact.hpp beside constraints/rolling_contact.py), so that a reader
    finds each formula's two implementations side by side; the build knows every header (setup.py's depends)."""
    import re

    kernels = sorted((PKG / "kernels").glob("*.hpp"))
    assert len(kernels) >= 10
    helpers = {"common", "lu_solve"}  # shared by the kernels, no Python twin of their own
    for path in kernels:
        head = path.read_text().split("#pragma once")[0]
        assert head.startswith(f"// robotdyn/kernels/{path.name}:"), path.name
        twins = [t for t in re.findall(r"robotdyn/([\w/]+)\.py", head) if (PKG / f"{t}.py").exists()]
        if path.stem.endswith("_derivatives"):  # a derivative kernel (issue 26, item 1): a Python derivatives module
            assert any(t.rpartition("/")[2].endswith("_derivatives") for t in twins), f"{path.name}: {twins}"
        elif path.stem not in helpers:
            assert any(t.rpartition("/")[2] == path.stem for t in twins), f"{path.name} names no Python twin {twins}"
    assert 'Path("robotdyn/kernels").glob("*.hpp")' in (PKG.parent / "setup.py").read_text()
