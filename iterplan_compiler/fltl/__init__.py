"""fltl stage of the iterplan compiler: fluents, FLTL safety automata and model checking.

* :mod:`.semantics` -- direct evaluator on traces (the oracle), formula alphabets;
* :mod:`.progression` -- FLTL -> generalised Büchi automaton over actions;
* :mod:`.emptiness` -- SCCs, live states, accepting lassos;
* :mod:`.safety` -- ``ltl_property``/``constraint`` -> minimal deterministic safety LTS;
* :mod:`.check` -- model checking of ``assert`` formulas on an LTS (fair by default).

Submodules are imported on demand; see ``docs/fltl.md``.
"""
