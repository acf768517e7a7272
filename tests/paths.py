"""Where the tests find the repository, whatever the depth of a test's folder: its root and the folders they read.
Importable as ``paths`` from any test (pytest puts ``tests/``, the folder of ``conftest.py``, on ``sys.path``)."""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"
DATA = TESTS / "data"  # the records the tests compare against
TOOLS = ROOT / "tools"
