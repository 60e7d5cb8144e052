import sys
from pathlib import Path

# Let the test modules import cli_helpers without making tests/ a package.
sys.path.insert(0, str(Path(__file__).parent))
