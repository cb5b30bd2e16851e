"""``python -m impact.cli``: the command line as it is imported (``impact`` and ``python -m impact`` choose the study's
kernel sets first)."""

import sys

from impact.cli import main

sys.exit(main())
