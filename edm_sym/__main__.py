"""``python -m edm_sym`` is ``edm``."""

import sys

from edm_sym.cli import main

sys.exit(main())
