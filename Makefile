# Developer entry points. `make test` is what CI runs (through .ci/run).
VENV ?= .venv
PY := $(VENV)/bin/python
PIP_PACKAGES := maturin numpy scipy pytest pytest-xdist mypy scikit-image matplotlib pandas pyarrow dask[distributed]
# The wheel's cargo profile: release for `make wheel`; `make test` builds it with the dev profile
# (assign and modal-core fully optimised, dependencies at opt-level 3 already compiled for
# `cargo test`), so that CI compiles the dependency tree once instead of twice.
WHEEL_PROFILE ?= release
# Every cargo command sees the venv's interpreter, so that pyo3 is configured once for all of them.
# Under `make test`, rustc is clippy-driver for the workspace's own crates (RUSTC_WORKSPACE_WRAPPER):
# the test build itself is linted with warnings as errors, with no second compilation (a separate
# `cargo clippy` needs a check build of every dependency: minutes on 2 cores).
CARGO_ENV = PATH=$(abspath $(VENV))/bin:$$PATH $(CARGO_LINT)
CARGO_LINT :=


.PHONY: doc-check fmt-check test test-rust test-rust-python test-python test-browser wheel-check examples venv wheel bench bench-python lint demo

# Every test: the formatting check first, then Rust (unit, integration, doc), Python (against the
# installed wheel) and the API documentation side by side, the wheel installed on its own in a
# fresh venv without Rust, every example, and the report in a browser.
test: WHEEL_PROFILE = dev
test: CARGO_LINT = RUSTC_WORKSPACE_WRAPPER=$(CLIPPY_DRIVER) CLIPPY_ARGS=-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__
test: fmt-check test-rust-python wheel-check examples test-browser
CLIPPY_DRIVER = $(shell command -v clippy-driver || echo clippy-driver-not-installed)

# One cargo invocation for every crate (pyo3 reads the venv's interpreter); the benchmarks are
# compiled too (with the test profile). The bindings are tested from Python (`make test-python`).
test-rust: venv
	$(CARGO_ENV) cargo test --workspace
	$(CARGO_ENV) cargo test -q --workspace --benches --no-run

# The API documentation with warnings as errors (broken or private links, bad code blocks).
DOC_ENV = PATH=$(abspath $(VENV))/bin:$$PATH RUSTDOCFLAGS="-D warnings"
doc-check: venv
	$(DOC_ENV) cargo doc -q --workspace --no-deps

# `make test`'s test stage: the Rust test build, then the Rust tests, the Python tests (against
# the wheel, built first) and the API documentation side by side, so that both cores stay busy:
# the Rust test binaries run one after another and often leave a core idle. rustdoc needs a check
# build of every dependency, which the test build cannot lend it, so it runs in a target folder
# of its own. The Python tests' and the documentation's output is shown, and their failure fails
# the stage, once the Rust tests are done. The benchmarks are left to `make lint` and
# `make test-rust` here (CI's time limit).
DOC_DIR := target/doc-check
PYTEST_LOG := target/pytest.log
test-rust-python: wheel
	$(CARGO_ENV) cargo test --workspace --no-run
	cd $(VENV) && ./bin/python -c 'import pymodal, sys; \
		sys.exit(0 if "site-packages" in pymodal.__file__ else "pymodal not imported from the wheel: " + pymodal.__file__)'
	mkdir -p $(DOC_DIR); \
	( $(DOC_ENV) CARGO_TARGET_DIR=$(DOC_DIR) cargo doc -q --workspace --no-deps ) >$(DOC_DIR)/log 2>&1 & doc=$$!; \
	( cd $(VENV) && ./bin/python -m pytest -q -p no:cacheprovider -n $(PYTEST_WORKERS) --dist loadgroup \
		$(abspath crates/pymodal/tests) ) >$(PYTEST_LOG) 2>&1 & py=$$!; \
	status=0; \
	$(CARGO_ENV) cargo test --workspace --no-fail-fast || status=$$?; \
	if wait $$py; then cat $(PYTEST_LOG); else cat $(PYTEST_LOG); echo "make: the Python tests failed" >&2; status=1; fi; \
	if wait $$doc; then cat $(DOC_DIR)/log; else cat $(DOC_DIR)/log; echo "make: the API documentation failed" >&2; status=1; fi; \
	exit $$status

venv: $(VENV)/.ready

# uv resolves and installs the packages in parallel (seconds rather than minutes with pip).
$(VENV)/.ready:
	python3 -m venv $(VENV)
	$(PY) -m pip install -q uv
	$(VENV)/bin/uv pip install -q --python $(PY) $(PIP_PACKAGES)
	touch $@

# Builds the wheel of the distribution `pedomatch` (import name `pymodal`; abi3: one wheel for
# CPython >= 3.9) into dist/ and installs it into the venv. Cargo rebuilds nothing when the sources have not changed.
wheel: venv
	rm -f dist/pedomatch-*.whl
	$(CARGO_ENV) $(VENV)/bin/maturin build --profile $(WHEEL_PROFILE) --strip --quiet -i $(PY) \
		-m crates/pymodal/Cargo.toml -o dist
	$(PY) -m pip install -q --force-reinstall --no-deps dist/pedomatch-*.whl

# The Python tests run against the installed wheel: from outside the source tree, so that
# `import pymodal` cannot resolve to crates/pymodal/python. On every core (pytest-xdist: one
# worker per core, tests handed out as workers free up, a module marked with an xdist_group kept
# on one worker); PYTEST_WORKERS=0 runs them in one process.
PYTEST_WORKERS ?= auto
test-python: wheel
	cd $(VENV) && ./bin/python -c 'import pymodal, sys; \
		sys.exit(0 if "site-packages" in pymodal.__file__ else "pymodal not imported from the wheel: " + pymodal.__file__)'
	cd $(VENV) && ./bin/python -m pytest -q -p no:cacheprovider -n $(PYTEST_WORKERS) --dist loadgroup $(abspath crates/pymodal/tests)

# The wheel on its own: a throw-away venv, pip (numpy from PyPI as a binary wheel), its metadata
# (distribution `pedomatch`, not the index's unrelated `pymodal`) and a small real match, with
# every directory holding cargo or rustc removed from PATH.
PYTHON3 := $(shell command -v python3)
NO_RUST_PATH = $(shell p=; for d in $$(echo "$$PATH" | tr : ' '); do \
	[ -x "$$d/cargo" ] || [ -x "$$d/rustc" ] || p="$$p$$d:"; done; echo "$${p%:}")
wheel-check: wheel
	set -e; tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; \
	export PATH="$(NO_RUST_PATH)" CARGO_HOME="$$tmp/none" RUSTUP_HOME="$$tmp/none"; \
	if command -v cargo || command -v rustc; then echo "Rust is still on PATH" >&2; exit 1; fi; \
	$(PYTHON3) -m venv "$$tmp/venv"; \
	"$$tmp/venv/bin/python" -m pip install -q --only-binary=:all: dist/pedomatch-*-cp39-abi3-*.whl; \
	cd "$$tmp" && "$$tmp/venv/bin/python" $(abspath crates/pymodal/tests/smoke_installed_wheel.py)

# Every example: one Rust example per crate (plus the assignment timing harness on small
# sizes), then the Python ones with the venv's interpreter against the installed wheel. Outputs
# go to a temporary folder, removed afterwards.
# One build of every example with the tests' feature set (no second build of the dependencies).
EXAMPLES := target/debug/examples
examples: wheel
	$(CARGO_ENV) cargo build -q --workspace --examples
	$(EXAMPLES)/solve_small
	$(EXAMPLES)/timing 200
	$(EXAMPLES)/match_contours
	$(EXAMPLES)/read_asf
	$(EXAMPLES)/run_recording
	tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && \
	$(PY) examples/match_two_frames.py --out "$$tmp/match.png" && test -s "$$tmp/match.png" && \
	$(PY) examples/run_recording.py --out-dir "$$tmp" && test -s "$$tmp/pairs.csv" && \
	$(PY) examples/spm1d_curves.py "$$tmp/study" examples/data/FrasP01L.asf crates/pedo-io/tests/data/tekscan-FrasP01L-11-20.csv && \
	test -s "$$tmp/study/study_curves.csv" && \
	$(PY) examples/spm_register_speed.py --iterations 200

# The demo's report.html in headless Chromium (Debian's `chromium`): drawn, playable, offline.
# Under .ci/run, Chromium may still be installing in the background (CHROMIUM_INSTALL): wait for it.
# The binary as the tests build it (the same features: nothing is rebuilt after `cargo test`).
test-browser: venv
	$(CARGO_ENV) cargo test -q --workspace --no-run
	@if [ -n "$$CHROMIUM_INSTALL" ]; then \
		until [ -e "$$CHROMIUM_INSTALL.ok" ]; do \
			if [ -e "$$CHROMIUM_INSTALL.failed" ]; then cat "$$CHROMIUM_INSTALL"; exit 1; fi; sleep 1; \
		done; fi
	python3 tests/browser/test_report.py target/debug/pedomatch

bench:
	cargo bench

# The Python peers (pycpd, POT) and the R-data reader (rdata) are only needed here, not by the tests.
bench-python: wheel
	$(PY) -m pip install -q pycpd pot rdata
	for s in benches/python/bench_*.py; do $(PY) $$s || exit 1; done

# Formatting (instant): part of `make test`, as are clippy (inside the test build) and rustdoc.
fmt-check:
	cargo fmt --all -- --check

# Formatting, clippy on every target of every crate, and the API documentation, each with
# warnings as errors (pymodal is in the workspace: pyo3 reads the venv's interpreter).
lint: venv
	cargo fmt --all -- --check
	$(CARGO_ENV) cargo clippy --workspace --all-targets -- -D warnings
	$(CARGO_ENV) RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps

demo:
	cargo run --release -- demo
