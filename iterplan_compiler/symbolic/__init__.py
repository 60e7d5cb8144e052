"""symbolic stage of the iterplan compiler."""
