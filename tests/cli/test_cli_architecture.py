"""The command line goes through one pipeline (iterplan_compiler/pipeline.py): the commands that
compile specs call its passes, not the front-end or synthesis directly, and no command is
loaded through importlib."""

from __future__ import annotations

import ast
from pathlib import Path

import iterplan_compiler
from iterplan_compiler import cli

PACKAGE = Path(iterplan_compiler.__file__).resolve().parent
SPEC_COMMANDS = ("check", "lts", "verify", "synth", "compile", "dot", "animate")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return out


def test_spec_commands_use_the_pipeline():
    for name in SPEC_COMMANDS:
        imports = _imports(PACKAGE / "commands" / f"{name}.py")
        assert "iterplan_compiler.pipeline" in imports, name
        # the passes, not their implementations
        assert not {"iterplan_compiler.frontend",
                    "iterplan_compiler.frontend.load_with_sources"} & imports, name


def test_no_importlib_for_own_modules():
    for rel in ("cli.py", "pipeline.py", *(f"commands/{c}.py" for c in cli.COMMANDS
                                           if c != "experiment")):
        text = (PACKAGE / rel).read_text(encoding="utf-8")
        assert "import_module" not in text and "find_spec" not in text, rel


def test_command_table_loads_every_command():
    for name, command in cli.COMMANDS.items():
        module = command.load()
        assert module.__name__.endswith(f".{name}") and callable(module.run), name
