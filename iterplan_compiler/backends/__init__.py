"""backends stage of the iterplan compiler."""
