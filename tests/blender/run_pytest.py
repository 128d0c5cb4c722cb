"""Runs pytest inside Blender:
  blender -b --factory-startup --python-exit-code 1 \
    --python tests/blender/run_pytest.py -- [pytest args]
"""
import os
import sys

import pytest

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
here = os.path.dirname(os.path.abspath(__file__))
args = argv or [here]
# -p no:cacheprovider: never write .pytest_cache into the source tree.
sys.exit(pytest.main(["-p", "no:cacheprovider", "-o", "console_output_style=classic"] + args))
