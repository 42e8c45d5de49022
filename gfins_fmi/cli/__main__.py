"""``python -m gfins_fmi.cli``: the ``gfins`` command."""
import sys

from gfins_fmi.cli import main

sys.exit(main())
