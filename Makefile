# pcsuite: `make report` and `make test` do the whole set-up on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
SUITE ?= default

.PHONY: all setup system-deps siconos warm check test package-check report bench clean

all: test

# ngspice and its shared library (PySpice loads libngspice.so), and Chromium with its driver for the
# report's browser test, and a C compiler for the ahead-of-time kernels, from the system package manager when missing.
APT_PACKAGES := ngspice libngspice0 libngspice0-dev chromium chromium-driver gcc
system-deps:
	@missing=""; \
	command -v ngspice >/dev/null 2>&1 || missing="yes"; \
	command -v gcc >/dev/null 2>&1 || missing="yes"; \
	[ -n "$$(ls /usr/lib/*/libngspice.so /usr/lib/libngspice.so 2>/dev/null)" ] || missing="yes"; \
	command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1 || missing="yes"; \
	if [ -n "$$missing" ]; then \
	  echo "installing $(APT_PACKAGES) with apt-get"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $(APT_PACKAGES) >/dev/null; \
	fi
	@ngspice --version 2>/dev/null | grep -o 'ngspice-[0-9.]*' | head -1

# constraints.txt: the versions the tests last passed with (a fresh machine gets those, not the latest release)
$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -c constraints.txt -e '.[test]'
	touch $(STAMP)

# The compiled kernels ahead of time (numba.pycc; converters/compiled.py says why): rebuilt when a kernel source
# (converters/kernel_cache.py SOURCES) changed, a no-op otherwise; 101 s on an idle 2-core machine, 4 to 7 min on a
# loaded one. A build that fails (no C compiler) leaves numba's JIT to do the same work.
setup: system-deps $(STAMP)
	-@$(PY) -m converters.build_kernels

# numba's JIT compiles every kernel once per checkout (validation/warm.py: small runs of the commands users type, in a
# process that forces the JIT; cached on disk beside the sources until a kernel source changes, and a stamp there says
# it is done): pay it here, once, rather than inside whichever test or run first calls a kernel. 51 s on an idle 2-core
# machine after the ahead-of-time build; a no-op when done.
warm: setup
	$(PY) -m validation.warm

# The fast tier, for the edit-run loop: every test but those that need ngspice (spice), build the package (package) or
# take more than 2 s (slow: report sections, bifurcation diagrams, fresh compiles, subprocess tables); FAST_TIER is the
# one selection, tests/test_marks.py checks it holds at least 80 % of the tests.
FAST_TIER := not slow and not spice and not package
check: setup warm
	$(PY) -m pytest -q -m "$(FAST_TIER)"

test: setup warm
	$(PY) -m pytest -q

# The package as a user installs it (tests/test_packaging.py, also in the test run above): an sdist and a wheel,
# the wheel in a fresh venv, pcsuite run from outside the checkout; 1.5 to 3 minutes.
package-check: setup
	$(PY) -m pytest -q tests/test_packaging.py

report: setup
	$(VENV)/bin/pcsuite report $(SUITE)

# Siconos (the peer of benchmarks/peers.py) from the system package manager, for the system Python, when missing.
siconos:
	@/usr/bin/python3 -c "import siconos.kernel" 2>/dev/null || { echo "installing python3-siconos with apt-get"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq python3-siconos >/dev/null \
	  || echo "python3-siconos could not be installed: benchmarks/peers.py will skip Siconos"; }

# Every benchmark the docs quote, one after another (side by side on a shared machine is noise): each writes its
# figures to benchmarks/results/NAME.json with the date and the machine (benchmarks/record.py), which the docs build
# substitutes (docs/hooks/figures.py). peers.py runs peer_lcp.py and tradeoff.py runs accuracy.py. A benchmark that
# misses its target exits non-zero: the others still run, and `make bench` fails at the end. About an hour.
BENCHMARKS := step_cost simulate_buck steady_rate lcp_entry time_limits memory spice_memory cam_siconos \
	event_scaling inverter bode gdcm_maps sweep tolerance netlist peers tradeoff report thermal
bench: setup siconos
	@status=0; for name in $(BENCHMARKS); do echo "== benchmarks/$$name.py"; \
	  $(PY) benchmarks/$$name.py || { echo "benchmarks/$$name.py exited $$?"; status=1; }; done; \
	echo "== benchmarks/bifurcation.py --event"; $(PY) benchmarks/bifurcation.py --event || status=1; exit $$status

clean:
	rm -rf $(VENV) reports/*/ build *.egg-info
