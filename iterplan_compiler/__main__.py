"""``python -m iterplan_compiler`` is the ``iterc`` command."""

import sys

from iterplan_compiler.cli import main

sys.exit(main())
