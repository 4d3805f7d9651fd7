# Developer entry points. `make test` is what CI runs (through .ci/run).
VENV ?= .venv
PY := $(VENV)/bin/python
PIP_PACKAGES := maturin numpy scipy pytest scikit-image matplotlib

.PHONY: test test-rust test-python test-browser venv wheel bench bench-python lint demo

# Every test: Rust (unit, integration, doc) and Python.
test: test-rust test-python test-browser

test-rust: venv
	cargo test
	PATH=$(abspath $(VENV))/bin:$$PATH cargo test -p pymodal

venv: $(VENV)/.ready

$(VENV)/.ready:
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q $(PIP_PACKAGES)
	touch $@

# Builds the pymodal wheel (release profile) and installs it into the venv.
wheel: venv
	$(PY) -m pip install -q --force-reinstall --no-deps ./crates/pymodal

test-python: wheel
	$(PY) -m pytest -q crates/pymodal/tests

# The demo's report.html in headless Chromium (Debian's `chromium`): drawn, playable, offline.
test-browser:
	cargo build --bin pedomatch
	python3 tests/browser/test_report.py target/debug/pedomatch

bench:
	cargo bench

# The Python peers (pycpd, POT) are only needed here, not by the tests.
bench-python: wheel
	$(PY) -m pip install -q pycpd pot
	for s in benches/python/bench_*.py; do $(PY) $$s || exit 1; done

lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings

demo:
	cargo run --release -- demo
