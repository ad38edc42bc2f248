#!/usr/bin/python3
"""The script `cullide plot` and `cullide report` run (tools/cli/plot.cpp; $CULLIDE_PLOT_SCRIPT
names another): charts of cullide's outputs and the study report, drawn by the package beside it,
tools/plotting/ (its docstring: the inputs and the charts; `plot.py --help`).
Needs matplotlib and numpy (Debian: /usr/bin/python3 with python3-matplotlib)."""
import os
import sys

# The package is found beside this script, in the source tree and where it is installed
# (share/cullide/tools); no bytecode is written there (an installed tree may be read-only).
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.dont_write_bytecode = True

from plotting.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
