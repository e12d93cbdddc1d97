"""``python -m monitor.cli``: the same as the ``fuzzrisk`` command."""
import sys

from monitor.cli import main

sys.exit(main())
