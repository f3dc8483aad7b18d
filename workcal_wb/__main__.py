"""``python3 -m workcal_wb``: the headless command line."""
import sys

from workcal_wb.cli import main

sys.exit(main())
