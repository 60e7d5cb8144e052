"""GR(1) controller synthesis with MTSA semantics (see docs/synthesis.md).

Entry point: :func:`iterplan_compiler.synthesis.driver.synthesize`.  Modules: ``encode``
(problem → game components), ``fixpoint`` (generic BDD GR(1) fixpoint), ``game`` (symbolic
game), ``explicit`` (explicit game + MTSA rank solver), ``strategy`` (controller extraction,
non-blocking), ``explain`` (unrealizability explanations), ``conformance`` (corpus checks).
Importing this package does not import ``dd``.
"""
