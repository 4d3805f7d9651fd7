# Developer entry points. `make test` is what CI runs (through .ci/run).
VENV ?= .venv
PY := $(VENV)/bin/python
PIP_PACKAGES := maturin numpy scipy pytest scikit-image matplotlib

.PHONY: test test-rust test-python examples venv wheel bench bench-python lint demo

# Every test: Rust (unit, integration, doc), Python, and every example.
test: test-rust test-python examples

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

# Every example: one Rust example per crate (plus the assignment timing harness on small
# sizes), then the Python ones with the venv's interpreter against the installed wheel. Outputs
# go to a temporary folder, removed afterwards.
examples: wheel
	cargo run -q -p assign --example solve_small
	cargo run -q -p assign --example timing -- 200
	cargo run -q -p modal-core --example match_contours
	cargo run -q -p pedo-io --example read_asf
	cargo run -q -p pedomatch --example run_recording
	tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && \
	$(PY) examples/match_two_frames.py --out "$$tmp/match.png" && test -s "$$tmp/match.png" && \
	$(PY) examples/run_recording.py --out-dir "$$tmp" && test -s "$$tmp/pairs.csv"

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
