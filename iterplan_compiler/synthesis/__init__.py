"""synthesis stage of the iterplan compiler."""
