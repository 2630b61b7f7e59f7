"""``python -m synmitsuba``: the same as the ``synmitsuba`` command."""
import sys

from synmitsuba.cli import main

sys.exit(main())
