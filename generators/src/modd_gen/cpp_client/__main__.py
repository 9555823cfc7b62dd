"""``python -m modd_gen.cpp_client``: refresh (or --check) the carried C++ sources."""

import sys

from . import main

sys.exit(main())
