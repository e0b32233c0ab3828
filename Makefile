# Modal Deform — build, test and run everything from a fresh Debian machine (as root).
#   make demo    install what is missing, build, bake and pose Suzanne headless -> out/demo.{blend,png}
#   make test    install, build, run the C++, Python and Blender tests
#   make bench   benchmarks (JSON in bench/results/, report and figures in docs/benchmarks.md, docs/figures/)

PYTHON      := /usr/bin/python3
BLENDER     := blender
BUILD_DIR   ?= build
JOBS        ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

# Debian packages the project needs, with the reason for each in README.md.
PACKAGES := cmake g++ make pkg-config \
	libeigen3-dev libspectra-dev libsuitesparse-dev libopenblas0-pthread zlib1g-dev \
	pybind11-dev python3-dev python3-numpy python3-scipy python3-pytest \
	libgtest-dev libbenchmark-dev \
	blender xvfb xauth python3-matplotlib

BLENDER_TEST := $(BLENDER) -b --factory-startup --python-exit-code 1

.PHONY: all deps build test test-cpp test-python test-blender test-gui demo bench bench-smoke addon clean

all: build

# Idempotent: asks dpkg first and only calls apt-get for what is missing.
deps:
	@missing=$$(for p in $(PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
		echo "Installing: $$missing"; \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing; \
	fi

build: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) $(CMAKE_FLAGS) -DPython_EXECUTABLE=$(PYTHON) > $(BUILD_DIR)/configure.log 2>&1 \
		|| (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	$(MAKE) --no-print-directory test-cpp test-python test-blender test-gui

test-cpp:
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

test-python:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/python

test-blender:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/blender

# Blender with a window under Xvfb, driven by simulated mouse and keyboard events.
test-gui:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/gui

demo: build
	@mkdir -p out
	$(BLENDER_TEST) --python blender_scripts/demo.py -- --output out

bench: build
	PYTHONPATH=python_addon $(PYTHON) bench/run.py

# Every experiment at tiny sizes (about a minute): results in bench/results/tmp/, no report.
bench-smoke: build
	PYTHONPATH=python_addon $(PYTHON) bench/run.py --quick

# dist/modal_deform-<version>.zip: the add-on folder with the compiled extension, for Blender's installer.
addon: build
	$(PYTHON) python_addon/package.py dist

clean:
	rm -rf $(BUILD_DIR) out dist python_addon/modal_deform/_native*.so
