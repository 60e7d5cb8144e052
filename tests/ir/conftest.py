import sys
from pathlib import Path

# Let the test modules import helpers_lts without making tests/ a package.
sys.path.insert(0, str(Path(__file__).parent))
