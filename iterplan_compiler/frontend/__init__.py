"""frontend stage of the iterplan compiler."""
