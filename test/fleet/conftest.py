"""pytest for scripts/pc_ekf_fleet (estimate_fleet's modules), without Dask:
test.sh runs `python3 -m pytest test/fleet`."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
