"""ir stage of the iterplan compiler."""
