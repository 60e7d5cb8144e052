"""The bundled examples (``examples/``) and the include library (``stdlib/``): where they are
and what each task is expected to do when flown.

Files are read through :mod:`importlib.resources`, so this works from a source checkout and
from an installed wheel alike.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path


@dataclass(frozen=True)
class Example:
    """One bundled task: its spec, the controller composite to synthesise, and its map."""

    name: str
    spec: str          # file name in examples/
    composite: str     # the `controller ||C` composite
    map: str | None    # map file in examples/ (runtime.grid.load_map schema)
    iterator: bool = True
    title: str = ""


EXAMPLES: dict[str, Example] = {
    e.name: e for e in (
        Example("fire_patrol", "fire_patrol.lts", "FirePatrol", "fire_patrol.json",
                title="Fire Patrol"),
        Example("find_nemo", "find_nemo.lts", "FindNemo", "find_nemo.json", title="Find Nemo"),
        Example("search_and_map", "search_and_map.lts", "SearchAndMap", "search_and_map.json",
                title="Search and Map Target"),
        Example("ordered_patrol", "ordered_patrol.lts", "OrderedPatrol", "ordered_patrol.json",
                title="Ordered Patrol"),
        Example("cover", "cover.lts", "Cover", "cover.json", title="Cover"),
        Example("fire_patrol_explicit", "fire_patrol_explicit.lts", "ExplicitFirePatrol", None,
                iterator=False, title="Fire Patrol, explicit locations"),
    )
}


def examples_dir() -> Path:
    """Directory holding the bundled examples (a real directory in both layouts we ship)."""
    return Path(str(resources.files("iterplan_compiler.examples")))


def stdlib_dir() -> Path:
    return Path(str(resources.files("iterplan_compiler.stdlib")))


def example_path(name_or_file: str) -> Path:
    """Path of a bundled example by task name (``fire_patrol``) or file name."""
    ex = EXAMPLES.get(name_or_file)
    return examples_dir() / (ex.spec if ex else name_or_file)


_CONST = r"(^\s*const\s+{name}\s*=\s*)([^\s/]+)"


def with_constant(text: str, name: str, value: int) -> str:
    """Spec text with ``const NAME = ...`` replaced by ``value`` (exactly one must exist)."""
    pattern = re.compile(_CONST.format(name=re.escape(name)), re.MULTILINE)
    new, n = pattern.subn(lambda m: f"{m.group(1)}{int(value)}", text)
    if n != 1:
        raise ValueError(f"expected exactly one 'const {name} = ...', found {n}")
    return new


def explicit_fire_patrol(n: int) -> str:
    """The explicit-location Fire Patrol spec with ``N = n`` patrol locations."""
    if n < 1:
        raise ValueError("N must be at least 1")
    text = example_path("fire_patrol_explicit").read_text()
    return with_constant(text, "N", n)
