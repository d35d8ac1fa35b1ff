# punctured_planner. A newcomer needs two commands: `make run` and `make test`.
#
# Both start with `make setup`: create .venv (Python 3.11), install the pinned
# ROS 2 Jazzy wheels and Python packages (requirements.txt + constraints.txt),
# build and install punctured_planner_interfaces into the venv prefix, and
# install this package (editable). Each step leaves a stamp file in
# .venv/.stamps whose name carries a hash of the step's inputs, so a second call
# does nothing; editing an input redoes that step and the ones after it.

SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
.DEFAULT_GOAL := help
.DELETE_ON_ERROR:

PYTHON ?= python3.11
VENV := .venv
ABS_VENV := $(CURDIR)/$(VENV)
VPY := $(VENV)/bin/python
STAMPS := $(VENV)/.stamps
IFACE := punctured_planner_interfaces
IFACE_BUILD := $(VENV)/build/$(IFACE)
PARAMS ?= config/default_scenario.yaml
PYTEST_ARGS ?=

# The venv is self-contained: a sourced ROS install or another venv must not leak in.
unexport PYTHONPATH PYTHONHOME AMENT_PREFIX_PATH CMAKE_PREFIX_PATH COLCON_PREFIX_PATH
unexport LD_LIBRARY_PATH _ROS_WHEELS_BOOTSTRAP_COMPLETE VIRTUAL_ENV

# hash of file names and contents, for stamp names
hash = $(shell { echo $(1); cat $(1); } 2>/dev/null | sha256sum | cut -c1-16)

WHEELS_KEY := $(call hash,requirements.txt constraints.txt)
IFACE_INPUTS := $(sort $(wildcard $(IFACE)/CMakeLists.txt $(IFACE)/package.xml \
	$(IFACE)/srv/*.srv $(IFACE)/msg/*.msg $(IFACE)/action/*.action))
IFACE_KEY := $(call hash,$(IFACE_INPUTS))
PROJECT_KEY := $(call hash,setup.py setup.cfg package.xml)

STAMP_WHEELS := $(STAMPS)/wheels-$(WHEELS_KEY)
STAMP_IFACE := $(STAMPS)/interfaces-$(IFACE_KEY)-$(WHEELS_KEY)
STAMP_PROJECT := $(STAMPS)/project-$(PROJECT_KEY)-$(IFACE_KEY)-$(WHEELS_KEY)

# Missing prerequisites stop the build with one line saying what to install.
SETUP_GOALS := $(filter setup test run bench,$(MAKECMDGOALS))
ifneq ($(filter lock,$(MAKECMDGOALS))$(if $(SETUP_GOALS),$(if $(wildcard $(VPY)),,x)),)
ifeq ($(shell command -v $(PYTHON)),)
$(error $(PYTHON) not found: install Python 3.11 (Debian 12: apt-get install python3.11 python3.11-venv))
endif
ifneq ($(shell $(PYTHON) -c 'import sys; print(sys.version_info[:2] == (3, 11))' 2>/dev/null),True)
$(error $(PYTHON) is not Python 3.11, which the ros-jazzy wheels need: install python3.11 or set PYTHON=/path/to/python3.11)
endif
ifneq ($(shell $(PYTHON) -c 'import ensurepip, venv' >/dev/null 2>&1 && echo ok),ok)
$(error $(PYTHON) cannot create virtual environments: install python3.11-venv (apt-get install python3.11-venv))
endif
endif
ifneq ($(SETUP_GOALS),)
ifeq ($(wildcard $(STAMP_IFACE)),)
ifeq ($(shell command -v cmake),)
$(error cmake not found: install cmake (apt-get install cmake))
endif
ifeq ($(shell command -v cc)$(shell command -v gcc),)
$(error no C compiler found: install build-essential (apt-get install build-essential))
endif
ifeq ($(shell command -v c++)$(shell command -v g++),)
$(error no C++ compiler found: install build-essential (apt-get install build-essential))
endif
endif
endif

PIP := $(VPY) -m pip
PIP_INSTALL := $(PIP) install --progress-bar off --disable-pip-version-check -q
# this machine's pip configuration names local index folders that may be empty
PIP_FILTER := { grep -v -e 'is ignored: it is neither a file nor a directory' || true; }

.PHONY: help setup test run bench demo lock clean

help:
	@echo 'make run    start the planner node in the foreground (after setup)'
	@echo 'make test   run the whole test suite: unit, lint, DDS, colcon (after setup)'
	@echo 'make setup  create .venv, install pinned packages, build the interfaces'
	@echo 'make bench  benchmarks beside OMPL (about 15 minutes): bench/results.md, results.png'
	@echo '           and plan execution over DDS: bench/execution.md'
	@echo 'make demo   simulated fleet + planner + executor: demo.mcap, demo.gif'
	@echo '            (DRIVE=differential: four TurtleBot-like differential robots)'
	@echo 'make lock   re-resolve requirements.txt into constraints.txt'
	@echo 'make clean  remove .venv and caches'

setup: $(STAMP_PROJECT)

$(VPY):
	@echo '==> creating $(VENV) with $(PYTHON)'
	@$(PYTHON) -m venv $(VENV)

$(STAMP_WHEELS): | $(VPY)
	@echo '==> installing pinned packages into $(VENV) (first time: about a minute)'
	@rm -f $(STAMPS)/wheels-*
	@$(PIP_INSTALL) -r requirements.txt -c constraints.txt 2>&1 | $(PIP_FILTER)
	@mkdir -p $(STAMPS) && touch $@

$(STAMP_IFACE): | $(STAMP_WHEELS)
	@echo '==> building $(IFACE) into $(VENV) (log: $(IFACE_BUILD).log)'
	@rm -f $(STAMPS)/interfaces-*
	@if [ -f $(IFACE_BUILD)/install_manifest.txt ]; then \
	  xargs -d '\n' rm -f < $(IFACE_BUILD)/install_manifest.txt; fi
	@rm -rf $(IFACE_BUILD) && mkdir -p $(IFACE_BUILD)
	@gen=$$(command -v ninja >/dev/null && echo '-GNinja' || true); \
	export AMENT_PREFIX_PATH=$(ABS_VENV); \
	{ cmake -S $(IFACE) -B $(IFACE_BUILD) $$gen -DCMAKE_BUILD_TYPE=Release \
	    -DCMAKE_PREFIX_PATH=$(ABS_VENV) -DCMAKE_INSTALL_PREFIX=$(ABS_VENV) \
	    -DPython3_EXECUTABLE=$(ABS_VENV)/bin/python3 -DBUILD_TESTING=OFF \
	  && cmake --build $(IFACE_BUILD) --parallel $$(nproc) \
	  && cmake --install $(IFACE_BUILD); } > $(IFACE_BUILD).log 2>&1 \
	|| { tail -n 30 $(IFACE_BUILD).log; \
	     echo 'error: building $(IFACE) failed, full log: $(IFACE_BUILD).log'; exit 1; }
	@touch $@

$(STAMP_PROJECT): | $(STAMP_IFACE)
	@echo '==> installing punctured_planner (editable) into $(VENV)'
	@rm -f $(STAMPS)/project-*
	@$(PIP_INSTALL) --no-deps --no-build-isolation --use-pep517 -e . 2>&1 | $(PIP_FILTER)
	@touch $@

test: setup
	$(VPY) -m pytest test/ $(PYTEST_ARGS)

# Not part of make test: about 15 minutes, and OMPL only installed here.
bench: setup
	@$(PIP_INSTALL) -r bench/requirements.txt -c constraints.txt 2>&1 | $(PIP_FILTER)
	$(VPY) bench/run_all.py $(BENCH_ARGS)
	$(VPY) bench/execution.py $(BENCH_ARGS)
	$(VPY) bench/feedforward.py
	$(VPY) bench/topology.py

# A simulated fleet, the planner and the executor: plan, execute, record (about a minute;
# two with DRIVE=differential).
# DRIVE=differential: four TurtleBot 4-like differential robots (config/demo_differential*).
DRIVE ?= holonomic
DEMO_ARGS_differential = --params config/demo_differential.yaml \
	--request config/demo_differential_request.yaml
demo: setup
	$(VPY) -m punctured_planner.demo $(DEMO_ARGS_$(DRIVE))

# Discovery stays on this machine unless ROS_AUTOMATIC_DISCOVERY_RANGE says otherwise.
run: setup
	@export ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}; \
	if [ -n '$(PARAMS)' ]; then \
	  echo '==> $(VENV)/bin/planner_node --ros-args --params-file $(PARAMS)'; \
	  exec $(VENV)/bin/planner_node --ros-args --params-file '$(PARAMS)'; \
	else \
	  echo '==> $(VENV)/bin/planner_node'; \
	  exec $(VENV)/bin/planner_node; \
	fi

# Resolve requirements.txt in a scratch venv and pin the full result in constraints.txt.
lock:
	@tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; \
	$(PYTHON) -m venv "$$tmp/venv"; \
	"$$tmp/venv/bin/pip" install --progress-bar off -q -r requirements.txt 2>&1 | $(PIP_FILTER); \
	{ echo '# Full pinned set for `pip install -r requirements.txt -c constraints.txt`.'; \
	  echo '# Generated by `make lock` from requirements.txt (Python 3.11); do not edit.'; \
	  "$$tmp/venv/bin/pip" freeze --all | grep -v -e '^pip==' ; } > constraints.txt
	@echo '==> constraints.txt updated'

clean:
	rm -rf $(VENV) *.egg-info .pytest_cache .hypothesis
