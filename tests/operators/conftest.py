"""Make this folder's helper modules (``rte_reference``) importable by its tests.

pytest runs with ``--import-mode=importlib``, which leaves ``sys.path`` alone.
"""

import sys
from pathlib import Path

HERE = str(Path(__file__).resolve().parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)
