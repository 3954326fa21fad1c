"""Every parameter of the public API is described in its docstring (Google style), as the API reference shows it.

The API reference (docs/api.rst) is generated recursively from every module of the ``robotdyn`` package whose
name has no component starting with ``_``, documenting (autodoc ``members``, module ``__all__`` ignored) the
public functions and classes defined in each module and the public methods defined in each class; a class's
constructor arguments are documented in the class docstring (``autodoc_class_signature = "separated"``). This
test walks the same set and fails, naming each, for any parameter without a description: under ``Args:`` (or
``Arguments:``, ``Keyword Args:``, ``Other Parameters:``), or for a class's constructor also under
``Attributes:`` (a dataclass's fields), as ``name: text``, ``name (type): text``, or ``a, b: text`` for several.
``self``, ``cls`` and ``*``/``**`` collectors documented as ``*args``/``args`` are handled alike; an overriding
method without a docstring of its own is checked against the docstring it inherits (as autodoc shows it).

The docstring examples (``Example:`` blocks, doctest format) of the entry points a user meets first are run by
``test_docstring_examples`` so that they cannot rot.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil
import re

import pytest

import robotdyn

SECTIONS = ("Args", "Arguments", "Keyword Args", "Keyword Arguments", "Other Parameters", "Parameters")


def public_modules() -> list:
    names = ["robotdyn"] + [m.name for m in pkgutil.walk_packages(robotdyn.__path__, "robotdyn.")]
    return [importlib.import_module(n) for n in sorted(names)
            if not any(part.startswith("_") for part in n.split("."))]


def described(doc: str | None, sections=SECTIONS) -> set[str]:
    """Names described in the given sections of a Google-style docstring."""
    out: set[str] = set()
    if not doc:
        return out
    lines = inspect.cleandoc(doc).splitlines()
    i = 0
    while i < len(lines):
        header = lines[i].strip()
        if header.endswith(":") and header[:-1] in sections and not lines[i].startswith(" "):
            i += 1
            indent = None
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith(" ")):
                line = lines[i]
                if line.strip():
                    width = len(line) - len(line.lstrip())
                    indent = width if indent is None else indent
                    if width == indent:
                        match = re.match(r"\s*([\w*][\w*, ]*?)\s*(\([^)]*\))?\s*:\s*(\S.*)?$", line)
                        if match:
                            for name in match.group(1).split(","):
                                out.add(name.strip().lstrip("*"))
                i += 1
            continue
        i += 1
    return out


def parameters(func) -> list[str]:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return []
    return [p.name for p in sig.parameters.values() if p.name not in ("self", "cls") and not p.name.startswith("_")]


def public_objects():
    """Every public module-level object defined in its own module: ``(qualified name, object)``."""
    for mod in public_modules():
        for name, obj in vars(mod).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
                continue
            yield f"{mod.__name__}.{name}", obj


def public_methods(cls):
    """A class's own public functions, static and class methods unwrapped, dataclass fields skipped (a field's
    default, e.g. a lambda, is data; properties are not functions): ``(name, function)``."""
    fields = getattr(cls, "__dataclass_fields__", {})
    for mname, member in cls.__dict__.items():
        if mname.startswith("_") or mname in fields:
            continue
        func = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
        if inspect.isfunction(func):
            yield mname, func


def missing_descriptions() -> list[str]:
    missing = []
    for where, obj in public_objects():
        if inspect.isfunction(obj):
            doc = described(obj.__doc__)
            missing += [f"{where}({p})" for p in parameters(obj) if p not in doc]
        elif inspect.isclass(obj):
            if issubclass(obj, BaseException):
                continue  # exceptions: a message, documented by the class
            init = obj.__dict__.get("__init__")
            ctor = init if init is not None and inspect.isfunction(init) else None
            if ctor is not None or "__dataclass_fields__" in obj.__dict__:
                doc = described(obj.__doc__, SECTIONS + ("Attributes",)) | described(getattr(ctor, "__doc__", None))
                names = parameters(ctor) if ctor is not None else parameters(obj)
                missing += [f"{where}({p})" for p in names if p not in doc]
            for mname, func in public_methods(obj):
                doc = described(inspect.getdoc(getattr(obj, mname)))  # inherited, as autodoc shows it
                missing += [f"{where}.{mname}({p})" for p in parameters(func) if p not in doc]
    return missing


def test_every_public_parameter_is_described():
    missing = missing_descriptions()
    assert not missing, f"{len(missing)} parameters without a description:\n" + "\n".join(missing)


def test_the_check_finds_an_undescribed_parameter():
    def f(a, b, *args, c=1, **kwargs):
        """Something.

        Args:
            a (int): First.
            *args: More.
            c: Keyword.
        """

    doc = described(f.__doc__)
    assert [p for p in parameters(f) if p not in doc] == ["b", "kwargs"]


EXAMPLES = (
    "robotdyn.load", "robotdyn.robots_available",
    "robotdyn.robot.Robot.reduced", "robotdyn.robot.Robot.forward_dynamics", "robotdyn.robot.Robot.inverse_dynamics",
    "robotdyn.robot.Robot.contact_forces", "robotdyn.interfaces.constraint_file.load_robot",
    "robotdyn.interfaces.constraint_file.read", "robotdyn.simulation.engine.simulate",
    "robotdyn.simulation.scenario.Scenario.run", "robotdyn.contact.traction.traction",
    "robotdyn.contact.contact_forces.constraint_forces", "robotdyn.sweep.runner.run",
    "robotdyn.interfaces.viewer.Viewer", "robotdyn.simulation.torque_profile.Constant",
    "robotdyn.simulation.trajectory.Trajectory.to_csv",
)
"""The entry points a user meets first: each has an ``Example:`` in doctest form, run here."""


def _resolve(dotted: str):
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for attr in parts[k:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(dotted)


@pytest.mark.parametrize("dotted", EXAMPLES)
def test_docstring_examples(dotted, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    obj = _resolve(dotted)
    tests = doctest.DocTestFinder(recurse=False).find(obj, dotted, globs={})
    examples = [t for t in tests if t.examples]
    assert examples, f"{dotted} has no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in examples:
        runner.run(t)
    assert runner.failures == 0, f"{runner.failures} failing example(s) in {dotted} (run pytest -rA for the diff)"


RETURN_SECTIONS = ("Returns", "Return", "Yields", "Yield")


def has_section(doc: str | None, sections=RETURN_SECTIONS) -> bool:
    """Whether a Google-style docstring has one of the given sections (a header line at the left margin)."""
    if not doc:
        return False
    return any(line.endswith(":") and line[:-1] in sections
               for line in inspect.cleandoc(doc).splitlines())


def _returns_a_value(func) -> bool:
    """Whether the function's own body (not a nested function's) has a ``return <value>`` (or is a generator)."""
    import ast
    import textwrap
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    node = next((n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))),
                None)
    if node is None or isinstance(node, ast.Lambda):  # a lambda returns its expression
        return node is not None
    stack = list(node.body)
    while stack:
        n = stack.pop()
        if isinstance(n, ast.Return) and n.value is not None and not (
                isinstance(n.value, ast.Constant) and n.value.value is None):
            return True
        if isinstance(n, (ast.Yield, ast.YieldFrom)):
            return True
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        stack.extend(ast.iter_child_nodes(n))
    return False


def needs_returns(func) -> bool:
    """A function needs ``Returns:``/``Yields:`` if annotated other than None, or unannotated and returning a value."""
    try:
        ann = inspect.signature(func).return_annotation
    except (TypeError, ValueError):
        return False
    if ann is inspect.Signature.empty:
        return _returns_a_value(func)
    return ann not in (None, "None", "NoReturn", "typing.NoReturn")


def missing_returns() -> list[str]:
    missing = []
    for where, obj in public_objects():
        if inspect.isfunction(obj):
            if needs_returns(obj) and not has_section(obj.__doc__):
                missing.append(where)
        elif inspect.isclass(obj) and not issubclass(obj, BaseException):
            for mname, func in public_methods(obj):
                if needs_returns(func) and not has_section(inspect.getdoc(getattr(obj, mname))):
                    missing.append(f"{where}.{mname}")
    return missing


def test_every_public_function_documents_what_it_returns():
    missing = missing_returns()
    assert not missing, f"{len(missing)} public functions without a Returns:/Yields: section:\n" + "\n".join(missing)


def test_the_check_finds_an_undocumented_return():
    def annotated(a) -> int:
        """Something.

        Args:
            a: First.
        """
        return a

    def unannotated(a):
        """Something."""
        def inner():
            return 1
        return a + inner()

    def nothing(a):
        """Something."""
        def inner():
            return 1
        inner()
        return

    def documented(a) -> tuple[int, int]:
        """Something.

        Returns:
            ``(a, a)``.
        """
        return a, a

    def generator(a):
        """Something.

        Yields:
            ``a`` once.
        """
        yield a

    def procedure(a) -> None:
        """Something."""

    lam = lambda a: a  # noqa: E731 (a public name bound to a lambda returns its expression)
    flagged = [f.__name__ for f in (annotated, unannotated, nothing, documented, generator, procedure, lam)
               if needs_returns(f) and not has_section(f.__doc__)]
    assert flagged == ["annotated", "unannotated", "<lambda>"]
