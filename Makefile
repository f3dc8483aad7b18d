# WorkCal: `make demo` and `make test` set up everything they need on Debian 12 or 13 (as root), then run.

PYTHON        := /usr/bin/python3
BUILD         := $(CURDIR)/build
FREECAD_HOME  := $(BUILD)/freecad-home
DEMO_DIR      := $(BUILD)/demo
DEB_PACKAGES  := freecad python3-numpy python3-scipy python3-open3d python3-matplotlib python3-pytest \
                 python3-hypothesis python3-pip python3-distributed xvfb xauth libgl1-mesa-dri
# The test peers' folder for this Python (see test-peers), told to the tests and the benchmark, which
# otherwise look under this checkout's build/: the other-Debian chroot builds elsewhere (BUILD=...).
PYTAG         := $(shell $(PYTHON) -c 'import sys; print(f"py{sys.version_info[0]}{sys.version_info[1]}")')
PEERS_ENV     := WORKCAL_TEST_PEERS=$(BUILD)/test-peers/$(PYTAG)
# Tests never touch the user's FreeCAD settings: a throw-away home with this checkout linked into Mod/.
FREECAD_ENV   := FREECAD_USER_HOME=$(FREECAD_HOME) QTWEBENGINE_DISABLE_SANDBOX=1 WORKCAL_TEST_OUTPUT=$(BUILD)/test-output \
                 WORKCAL_REQUIRE_PYE57=1 $(PEERS_ENV)
# The first X display number tried: the other-Debian chroot shares the network namespace (X's abstract
# sockets) but not /tmp (its lock files), so it starts elsewhere and both suites can run at once.
XVFB_DISPLAY  ?= 99
# Extra pytest arguments for the GUI tests (e.g. GUI_PYTEST_ARGS="-k guide"); empty: all of them.
GUI_PYTEST_ARGS ?=
XVFB          := xvfb-run -a -n $(XVFB_DISPLAY) -s "-screen 0 1280x1024x24"
# -rfEs: each failure, error and skip named (with why) in the CI log; --durations: the slowest tests, the first to trim (CI must stay well under 30 min).
# PySide2 under Python 3.13 warns about every type it defines as it is imported: noise, not ours.
PYTEST_ARGS   := -q -rfEs --durations=10 -p no:cacheprovider --rootdir=$(CURDIR) -W ignore::DeprecationWarning:importlib._bootstrap

.PHONY: setup python-packages peers test-peers demo test test-headless test-fast test-gui test-other-freecad fuzz bench bench-verdicts \
        bench-scenes bench-processes bench-large bench-matcher bench-lblock bench-reach clean

setup:
	@.ci/install-debian-packages $(DEB_PACKAGES)
	@mkdir -p $(FREECAD_HOME)/Mod
	@ln -sfn $(CURDIR) $(FREECAD_HOME)/Mod/WorkCal

# pye57 (E57 scans; not a Debian package) into the folder FreeCAD adds to sys.path in the throw-away home.
python-packages: setup
	@.ci/install-python-packages $(FREECAD_HOME) pye57 pyquaternion

demo: setup
	$(PYTHON) -m workcal_wb demo --out $(DEMO_DIR)

test: test-headless test-gui

test-headless: setup python-packages test-peers
	$(FREECAD_ENV) freecadcmd -c "import sys, pytest; \
	rc = pytest.main('$(PYTEST_ARGS) $(CURDIR)/tests/core $(CURDIR)/tests/fc'.split()); sys.stdout.flush(); sys.exit(rc)"

# The headless tests that need no whole calibration, global search, benchmark run or real-scan study (the
# rest are marked slow): a few minutes, for checks while developing.  `make test` still runs every test.
test-fast: setup python-packages test-peers
	$(FREECAD_ENV) freecadcmd -c "import sys, pytest; \
	rc = pytest.main('$(PYTEST_ARGS) $(CURDIR)/tests/core $(CURDIR)/tests/fc'.split() + ['-m', 'not slow']); \
	sys.stdout.flush(); sys.exit(rc)"

test-gui: setup
	$(FREECAD_ENV) WORKCAL_GUI_PYTEST_ARGS="$(GUI_PYTEST_ARGS)" $(XVFB) freecad $(CURDIR)/tests/gui/run_gui_tests.py

# The same suites on the other Debian release (FreeCAD 1.0 from Debian 12, 0.20 from Debian 13), in a
# debootstrap chroot cached under build/ (see .ci/other-debian).
test-other-freecad:
	.ci/other-debian test

# Every reader with many more mutated files than `make test` tries (200 per kind there), fresh randomness.
FUZZ_EXAMPLES ?= 20000
fuzz: setup
	WORKCAL_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PYTHON) -m pytest $(PYTEST_ARGS) $(CURDIR)/tests/core/test_fuzz.py

# An independent solver the robot kinematics tests check ours against (tests only, never a runtime
# dependency), one folder per Python (the chroot's other Debian has another); without network it skips.
test-peers: setup
	@[ -d $(BUILD)/test-peers/$(PYTAG)/py_opw_kinematics ] || $(PYTHON) -m pip install --quiet --root-user-action=ignore --no-deps \
	    --target $(BUILD)/test-peers/$(PYTAG) py-opw-kinematics || echo "WorkCal: py-opw-kinematics not installed: its cross-checks skip"

# The whole-process table's second peer, from PyPI into build/peers (the benchmark's only; never a runtime
# dependency). --no-deps: Debian's numpy stays the one every process imports.
peers: setup
	@[ -d $(BUILD)/peers/kiss_matcher ] || $(PYTHON) -m pip install --quiet --no-deps --target $(BUILD)/peers \
	    kiss-matcher small-gicp

bench: setup peers
	$(PEERS_ENV) $(PYTHON) -m workcal_wb bench --out $(CURDIR)/docs/benchmarks.md

# Only the whole-process table (match and calibrate as processes, cold and warm, beside the peers).
bench-processes: setup peers
	$(PYTHON) -m workcal_wb bench --only processes --out $(CURDIR)/docs/benchmarks.md

# Only the matcher table (WorkCal beside stock Open3D, same cases; the G-code throughput), replacing the top of docs/benchmarks.md.
bench-matcher: setup
	$(PYTHON) -m workcal_wb bench --only matcher --out $(CURDIR)/docs/benchmarks.md

# Only the large-scan table (match as a process on 5M- and 20M-point PLY scans, written once into build/bench-large).
bench-large: setup
	$(PYTHON) -m workcal_wb bench --only large --out $(CURDIR)/docs/benchmarks.md

# Only the verdicts table (a few minutes), replacing its section of docs/benchmarks.md.
bench-verdicts: setup
	$(PYTHON) -m workcal_wb bench --only verdicts --out $(CURDIR)/docs/benchmarks.md

# Only the scenes table (cell scans calibrated with automatic regions), replacing its section of docs/benchmarks.md.
bench-scenes: setup
	$(PYTHON) -m workcal_wb bench --only scenes --out $(CURDIR)/docs/benchmarks.md

# Only the L-block on its foot (100 scenes of a reference that nearly maps onto itself turned over), its own section.
bench-lblock: setup
	$(PYTHON) -m workcal_wb bench --only lblock --workers 2 --out $(CURDIR)/docs/benchmarks.md

# Only the reach-check table (check_reach on a million poses beside py-opw-kinematics), replacing its section.
bench-reach: setup test-peers
	$(PEERS_ENV) $(PYTHON) -m workcal_wb bench --only reach --out $(CURDIR)/docs/benchmarks.md

# Never while the other-Debian chroot has /dev or /sys mounted: rm would reach through the mounts.
clean:
	@! grep -q " $(BUILD)/" /proc/self/mountinfo || { echo "make clean: something is mounted under $(BUILD); not removing it" >&2; exit 1; }
	rm -rf $(BUILD)
