"""commands stage of the iterplan compiler."""
