# pcsuite: `make report` and `make test` do the whole set-up on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
SUITE ?= default

.PHONY: all setup system-deps test report bench clean

all: test

# ngspice and its shared library (PySpice loads libngspice.so) from the system package manager.
system-deps:
	@if ! command -v ngspice >/dev/null 2>&1 || [ -z "$$(ls /usr/lib/*/libngspice.so /usr/lib/libngspice.so 2>/dev/null)" ]; then \
	  echo "installing ngspice, libngspice0 and libngspice0-dev with apt-get"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq ngspice libngspice0 libngspice0-dev >/dev/null; \
	fi
	@ngspice --version 2>/dev/null | grep -o 'ngspice-[0-9.]*' | head -1

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

setup: system-deps $(STAMP)

test: setup
	$(PY) -m pytest -q

report: setup
	$(VENV)/bin/pcsuite report $(SUITE)

bench: setup
	$(PY) benchmarks/step_cost.py

clean:
	rm -rf $(VENV) reports/*/ build *.egg-info
