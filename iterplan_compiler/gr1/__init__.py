"""GR(1) games over Boolean variables (slugs input format) solved with the symbolic engine."""
