"""Reproduction of the paper's experiments (Fig. 3 (b)-(d)) and the synthesis-time table.

* :mod:`.stats` — mean, standard error, the paper's "ideal" durations.
* :mod:`.sweeps` — what each figure varies (sizes, sorters, seeds) and how a case's map is built.
* :mod:`.harness` — runs the cases (in parallel processes, or on Dask), writes CSV, progress.
* :mod:`.plots` — matplotlib figures in the style of Fig. 3.
* :mod:`.missions` — one simulated mission per case, on top of the runtime and the compiler.
* :mod:`.synthesis_table` — iterator-based vs explicit-location synthesis times.

The command line is ``iterc experiment fig3b|fig3c|fig3d|synthesis-table``.
"""
