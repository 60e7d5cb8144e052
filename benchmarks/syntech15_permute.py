"""Declaration-order variants of the SYNTECH15 files, to measure how much the solver's time
depends on the order a spec happens to be written in (the verdict cannot change).

    python benchmarks/syntech15_permute.py OUT [--from FOLDER] [--seeds 1 2] [--shuffle env,sets,blocks]
    python benchmarks/syntech15_bench.py OUT

Each file of FOLDER (default: ../shared/benchmarks/syntech15, its ``unrealizable/`` kept as
such) is written to OUT once per seed as ``<name>_p<seed>.fsp`` with, shuffled by that seed:

* ``env``: the operands of ``||Env = (...)`` — the order of the components, hence of the
  BDD variables (the synthesis declares them component by component);
* ``sets``: the members of ``set ControlledActions`` / ``set UncontrolledActions``;
* ``blocks``: the variable blocks (``set X_Actions`` and its fluents) after ``AllActions``.

FSP gives all three no meaning (parallel composition is commutative, sets are sets, the
blocks only declare names), so every variant has its original's verdict.  Measured results:
docs/synthesis.md, "Declaration order".
"""

from __future__ import annotations

import argparse
import random
import re
import sys
from pathlib import Path

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "syntech15"
SHUFFLES = ("env", "sets", "blocks")


def _shuffled(items: list[str], rng: random.Random) -> list[str]:
    out = list(items)
    rng.shuffle(out)
    return out


def shuffle_set(text: str, name: str, rng: random.Random) -> str:
    """The members of ``set NAME = {...}`` in a random order."""
    m = re.search("set " + re.escape(name) + r" = \{([^}]*)\}", text)
    if m is None:
        raise ValueError(f"no 'set {name} = {{...}}'")
    items = _shuffled([x.strip() for x in m.group(1).split(",")], rng)
    return text[:m.start(1)] + ", ".join(items) + text[m.end(1):]


def shuffle_env(text: str, rng: random.Random) -> str:
    """The operands of ``||Env = (A || B || ...).`` in a random order."""
    m = re.search(r"\|\|Env = \((.*?)\)\.", text, re.S)
    if m is None:
        raise ValueError("no '||Env = (...).'")
    ops = _shuffled([x.strip() for x in m.group(1).split("||")], rng)
    return text[:m.start(1)] + " || ".join(ops) + text[m.end(1):]


def shuffle_blocks(text: str, rng: random.Random) -> str:
    """The variable blocks between ``set AllActions`` and the clock, in a random order."""
    head = text.find("set AllActions")
    end = text.find("// move from synchronous")
    if head < 0 or end < 0:
        raise ValueError("no variable blocks between 'set AllActions' and the clock")
    start = text.index("\n", head) + 1
    blocks = [b for b in re.split(r"\n(?=set )", text[start:end].strip()) if b.strip()]
    return text[:start] + "\n\n" + "\n\n".join(_shuffled(blocks, rng)) + "\n\n\n" + text[end:]


def permute(text: str, seed: int, shuffles: tuple[str, ...] = SHUFFLES) -> str:
    """``text`` with the chosen parts shuffled by ``seed`` (module doc)."""
    rng = random.Random(seed)
    if "sets" in shuffles:
        text = shuffle_set(text, "ControlledActions", rng)
        text = shuffle_set(text, "UncontrolledActions", rng)
    if "env" in shuffles:
        text = shuffle_env(text, rng)
    if "blocks" in shuffles:
        text = shuffle_blocks(text, rng)
    return text


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--from", dest="src", type=Path, default=DEFAULT)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--shuffle", default=",".join(SHUFFLES),
                    help=f"comma-separated subset of {','.join(SHUFFLES)}")
    args = ap.parse_args(argv)
    shuffles = tuple(s for s in args.shuffle.split(",") if s)
    if not shuffles or any(s not in SHUFFLES for s in shuffles):
        ap.error(f"--shuffle takes a subset of {','.join(SHUFFLES)}")
    files = sorted(args.src.glob("*.fsp")) + sorted(args.src.glob("unrealizable/*.fsp"))
    if not files:
        print(f"no .fsp files in {args.src}", file=sys.stderr)
        return 2
    for path in files:
        rel = path.relative_to(args.src)
        text = path.read_text()
        for seed in args.seeds:
            dst = args.out / rel.parent / f"{path.stem}_p{seed}.fsp"
            dst.parent.mkdir(parents=True, exist_ok=True)
            try:
                dst.write_text(permute(text, seed, shuffles))
            except ValueError as e:
                print(f"{rel}: {e}; skipped", file=sys.stderr)
    print(f"{len(files)} files x {len(args.seeds)} seeds -> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
