"""BDD utilities over ``dd`` (``bdd.new_manager``: dd.cudd if importable, else dd.autoref)."""
