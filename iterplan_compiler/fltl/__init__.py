"""fltl stage of the iterplan compiler."""
