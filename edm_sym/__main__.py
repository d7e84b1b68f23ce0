"""``python -m edm_sym`` is ``edm``."""

import sys

from edm_sym.application.cli import run

sys.exit(run())
