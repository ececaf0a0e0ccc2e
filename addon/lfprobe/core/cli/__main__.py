"""``python -m lfprobe.core.cli``: the lfprobe command line."""

import sys

from .main import main

sys.exit(main())
