"""Shared fixtures: bundled examples compiled once per test session."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from iterplan_compiler.experiments import catalog
from iterplan_compiler.experiments.pipeline import compile_example


class Compiled:
    """Compiles bundled examples on first use into one session directory."""

    def __init__(self, root: Path):
        self.root = root
        self.modules: dict[str, Path] = {}

    def module(self, name: str) -> Path:
        if name not in self.modules:
            self.modules[name], _ = compile_example(name, self.root)
        return self.modules[name]

    @staticmethod
    def map(name: str):
        from iterplan_compiler.runtime.mapfile import load_map

        path = catalog.examples_dir() / catalog.EXAMPLES[name].map
        return load_map(path), json.loads(path.read_text())


@pytest.fixture(scope="session")
def compiled(tmp_path_factory) -> Compiled:
    return Compiled(tmp_path_factory.mktemp("controllers"))
