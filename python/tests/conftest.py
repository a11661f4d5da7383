"""conftest.py - python/tests run with `python3 -m pytest python/tests` (ctest does it with
FLOE_LIBRARY set to the libfloe.so it built): the package is imported from python/."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
