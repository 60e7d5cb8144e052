"""Architecture rules of the guide, checked on the source tree (issue #12's done-when).

- no module over 500 lines, no function over 80 lines;
- no import cycles between modules, no upward imports between layers (table below);
- no ``importlib`` loading of the project's own modules (static imports only);
- ``runtime/`` imports without lark or dd (it ships to the companion computer);
- every command-line ``choices=`` is built from an enum (``[m.value for m in SomeEnum]``, or a
  module constant built that way): options are enums, not string lists (issue #12).

Imports under ``if TYPE_CHECKING:`` are annotations only and do not count.
"""

from __future__ import annotations

import argparse
import ast
import enum
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "iterplan_compiler"
ROOT = "iterplan_compiler"
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80

# Layers, lowest first: a module may import its own layer or lower ones, never higher.
# ``runtime`` and its clients form their own column: runtime imports only ``outputs`` below it.
LAYERS: dict[str, int] = {
    "": 0, "diagnostics": 0, "enums": 0, "limits": 0, "outputs": 0, "symbolic": 0,
    "runtime": 1,
    "ir": 1,
    "fltl": 2,
    "frontend": 3,
    "synthesis": 4,
    "gr1": 5,
    "backends": 6,
    "pipeline": 7,
    "conformance": 8, "conformance_checks": 8, "experiments": 8, "oracle": 8,
    "view": 9, "mavproxy": 9, "commands": 9,
    "cli": 10, "__main__": 11,
}
RUNTIME_MAY_IMPORT = {"", "outputs", "runtime"}


def _modules() -> dict[str, Path]:
    mods: dict[str, Path] = {}
    for path in sorted(PKG.rglob("*.py")):
        parts = (ROOT,) + path.relative_to(PKG).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        mods[name] = path
    return mods


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def _imports(name: str, path: Path, mods: dict[str, Path]) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = _type_checking_lines(tree)
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [mod] + [f"{mod}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            continue
        found.update(t for t in targets if t in mods and t != name)
    return found


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    return {name: _imports(name, path, mods) for name, path in mods.items()}


def _layer_key(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_module_and_function_sizes() -> None:
    long_modules, long_functions = [], []
    for name, path in _modules().items():
        text = path.read_text(encoding="utf-8")
        n = len(text.splitlines())
        if n > MAX_MODULE_LINES:
            long_modules.append(f"{name}: {n} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = (node.end_lineno or node.lineno) - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    long_functions.append(f"{name}.{node.name}: {length} lines")
    assert not long_modules, f"modules over {MAX_MODULE_LINES} lines: {long_modules}"
    assert not long_functions, f"functions over {MAX_FUNCTION_LINES} lines: {long_functions}"


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                out.append(sorted(scc))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles() -> None:
    graph = _graph()
    # A package's __init__ re-exporting its own submodules is not a cycle of the design.
    for name in graph:
        graph[name] = {t for t in graph[name] if not name.startswith(t + ".")}
    assert _cycles(graph) == []


def test_no_upward_imports() -> None:
    bad = []
    for name, targets in _graph().items():
        src = _layer_key(name)
        assert src in LAYERS, f"{name}: add its package to LAYERS"
        for target in targets:
            dst = _layer_key(target)
            assert dst in LAYERS, f"{target}: add its package to LAYERS"
            if src == "runtime" and dst not in RUNTIME_MAY_IMPORT:
                bad.append(f"{name} -> {target} (runtime imports only outputs)")
            elif src != "runtime" and dst == "runtime" and LAYERS[src] < 6:
                bad.append(f"{name} -> {target} (compiler core must not need the runtime)")
            elif dst != "runtime" and LAYERS[dst] > LAYERS[src]:
                bad.append(f"{name} -> {target} (upward: {src} below {dst})")
    assert bad == []


def test_no_importlib_of_own_modules() -> None:
    bad = []
    for name, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call):
                continue
            func = ast.unparse(node.func)
            if func.endswith(("import_module", "find_spec", "__import__")) and node.args:
                arg = ast.unparse(node.args[0])
                if ROOT in arg or arg.startswith(("'.", '".')) or "module" in arg:
                    bad.append(f"{name}:{node.lineno}: {func}({arg})")
    assert bad == []


@pytest.mark.parametrize("blocked", ["lark", "dd"])
def test_runtime_imports_without(blocked: str) -> None:
    code = (
        "import sys\n"
        f"class Block:\n"
        f"    def find_spec(self, name, path=None, target=None):\n"
        f"        if name == {blocked!r} or name.startswith({blocked!r} + '.'):\n"
        f"            raise ImportError('blocked: ' + name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "import pkgutil, importlib\n"
        "import iterplan_compiler.runtime as rt\n"
        "for m in pkgutil.iter_modules(rt.__path__):\n"
        "    importlib.import_module('iterplan_compiler.runtime.' + m.name)\n"
        f"assert not any(k == {blocked!r} or k.startswith({blocked!r} + '.') for k in sys.modules)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=PKG.parent)


def test_graph_sees_imports() -> None:
    """The checks above can fail: the graph finds known edges."""
    graph = _graph()
    assert "iterplan_compiler.runtime.iterator" in graph["iterplan_compiler.runtime.executor"]
    assert _cycles({"a": {"b"}, "b": {"a"}}) == [["a", "b"]]


# -- CLI choices come from enums (issue #12: enums, not option strings) -----------------------


def _enum_comprehension(expr: ast.expr) -> bool:
    """``[m.value for m in E (if ...)]`` (or a generator/set, or ``tuple(...)``/``list(...)``
    of one) over a name or attribute, i.e. an enum class, not over a literal."""
    if isinstance(expr, ast.Call) and isinstance(expr.func, ast.Name) \
            and expr.func.id in ("tuple", "list", "sorted") and len(expr.args) == 1:
        expr = expr.args[0]
    if not isinstance(expr, (ast.ListComp, ast.GeneratorExp, ast.SetComp)):
        return False
    gen = expr.generators
    return (len(gen) == 1 and isinstance(gen[0].iter, (ast.Name, ast.Attribute))
            and isinstance(expr.elt, ast.Attribute) and expr.elt.attr == "value")


def _choices_from_enum(module: str, expr: ast.expr, trees: dict[str, ast.Module]) -> bool:
    """``expr`` (the ``choices=`` of an ``add_argument`` in ``module``) is an enum
    comprehension, or a name bound at module level, here or where it is imported from, to one."""
    if _enum_comprehension(expr):
        return True
    if not isinstance(expr, ast.Name) or module not in trees:
        return False
    tree = trees[module]
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == expr.id for t in node.targets):
            return _enum_comprehension(node.value)
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) \
                and node.target.id == expr.id and node.value is not None:
            return _enum_comprehension(node.value)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and not node.level \
                and any((a.asname or a.name) == expr.id for a in node.names):
            return _choices_from_enum(node.module, ast.Name(expr.id), trees)
    return False


def test_cli_choices_are_built_from_enums() -> None:
    trees = {name: ast.parse(path.read_text(encoding="utf-8"))
             for name, path in _modules().items()}
    found, bad = 0, []
    for name, tree in trees.items():
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "add_argument"):
                continue
            for kw in node.keywords:
                if kw.arg == "choices":
                    found += 1
                    if not _choices_from_enum(name, kw.value, trees):
                        bad.append(f"{name}:{node.lineno}: choices={ast.unparse(kw.value)}")
    assert found >= 20, found  # the check sees the commands' options
    assert bad == [], "build these choices from an enum ([m.value for m in E]): " + str(bad)


def test_cli_choices_are_enum_values() -> None:
    """The parsers as built: every option with choices offers values of one enum, which
    parses each of them (so the command turns the string into the enum with ``E(value)``)."""
    from iterplan_compiler import cli

    parsers = [p for name in cli.COMMANDS for p in _all_parsers(cli.build_parser(only=name))]
    enums = _all_enums()
    bad, seen = [], 0
    for parser in parsers:
        for action in parser._actions:
            if not action.choices or isinstance(action, argparse._SubParsersAction):
                continue
            seen += 1
            values = set(action.choices)
            if not any(values <= {m.value for m in e} for e in enums):
                bad.append(f"{parser.prog} {'/'.join(action.option_strings) or action.dest}")
    assert seen >= 20, seen
    assert bad == []


def _all_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    out = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                out.extend(_all_parsers(sub))
    return out


def _all_enums() -> list[type[enum.Enum]]:
    out: list[type[enum.Enum]] = []
    for name in _modules():
        mod = sys.modules.get(name)
        if mod is None:
            continue  # only what building the parsers imported
        out.extend(v for v in vars(mod).values()
                   if isinstance(v, type) and issubclass(v, enum.Enum) and v is not enum.Enum)
    return out
