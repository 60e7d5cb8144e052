"""Bundled examples, maps, stdlib fragments and the explicit-location generator."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from iterplan_compiler.experiments import catalog
from iterplan_compiler.runtime.mapfile import load_map

ITERATOR_EXAMPLES = [e for e in catalog.EXAMPLES.values() if e.iterator]


def test_every_example_file_exists():
    for ex in catalog.EXAMPLES.values():
        assert catalog.example_path(ex.name).is_file(), ex.spec
        if ex.map:
            assert (catalog.examples_dir() / ex.map).is_file(), ex.map
    for frag in ("iterator.lts", "uav.lts", "sensors.lts"):
        assert (catalog.stdlib_dir() / frag).is_file()


@pytest.mark.parametrize("ex", ITERATOR_EXAMPLES, ids=lambda e: e.name)
def test_iterator_examples_use_the_iterator_and_phi0(ex):
    text = catalog.example_path(ex.name).read_text()
    assert 'include "iterator.lts"' in text
    assert "liveness = {HasNextInfinitelyOften}" in text
    assert re.search(rf"controller\s+\|\|{ex.composite}\s*=", text)
    # locations are never named in an iterator-based spec
    assert not re.search(r"\bgo\[", text)


@pytest.mark.parametrize("ex", ITERATOR_EXAMPLES, ids=lambda e: e.name)
def test_maps_load_and_define_the_sensors_the_spec_asks(ex):
    grid = load_map(catalog.examples_dir() / ex.map)
    text = catalog.example_path(ex.name).read_text()
    m = re.search(r"set NextSensorNames = \{([^}]*)\}", text)
    assert m, "spec declares its next-location sensors"
    derived = {"adjacent"}  # computed at run time from store.target
    for name in (s.strip() for s in m.group(1).split(",")):
        if name.startswith("p["):
            n = int(re.search(r"const N = (\d+)", text).group(1))
            for i in range(n):
                assert len(grid.sensors[f"p.{i}"]) == 1
        elif name not in derived:
            assert len(grid.sensors[name]) > 0, name
    assert len(grid.cells) >= 64


def test_fire_patrol_map_fires_are_patrol_cells():
    grid = load_map(catalog.examples_dir() / "fire_patrol.json")
    assert set(grid.sensors["fire"]) <= set(grid.sensors["inP"])
    assert {grid.cell_name(c) for c in grid.sensors["inP"]} >= {"C5", "A2", "B2"}


def test_with_constant_replaces_exactly_one():
    text = "const N = 3\nrange L = 0..N-1\n"
    assert catalog.with_constant(text, "N", 7).startswith("const N = 7\n")
    with pytest.raises(ValueError):
        catalog.with_constant(text, "M", 2)


@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_explicit_generator_sets_n_and_keeps_structure(n):
    text = catalog.explicit_fire_patrol(n)
    assert re.findall(r"^const N = (\d+)", text, re.MULTILINE) == [str(n)]
    assert "controller ||ExplicitFirePatrol" in text
    assert "fluent Patrolled[j:L]" in text
    assert text.count("(") == text.count(")") and text.count("{") == text.count("}")
    with pytest.raises(ValueError):
        catalog.explicit_fire_patrol(0)


def test_generator_script(tmp_path):
    out = tmp_path / "fp4.lts"
    r = subprocess.run([sys.executable, "benchmarks/gen_explicit_fire_patrol.py", "4", "-o",
                        str(out)], capture_output=True, text=True, cwd=_root())
    assert r.returncode == 0, r.stderr
    assert "const N = 4" in out.read_text()


def _root():
    from pathlib import Path

    return Path(__file__).resolve().parents[2]
