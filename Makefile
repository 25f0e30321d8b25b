# wearcoef: `make figures` rebuilds every artifact and figure of a profile; `make test` runs
# the whole test suite (format, the features check, lint, tests). Build products go to a fixed
# directory outside the clone so that repeated fresh clones (CI) reuse them. The tests run in
# release, where the binary is built anyway (one build of the dependencies, not two), all of
# them, those `#[ignore]`d as slow in debug included; the numerical core's run again in debug
# too, for its overflow checks and debug assertions.
CARGO_TARGET_DIR ?= /var/tmp/wearcoef-target
export CARGO_TARGET_DIR
PROFILE ?= default
JOBS ?= $(shell nproc)
BIN := $(CARGO_TARGET_DIR)/release/wearcoef

.PHONY: figures benchmarks build test test-client test-measured test-python test-report test-slurm slurm-start slurm-stop fmt clippy bench bench-fft bench-solver bench-peers bench-plastic bench-iteration bench-warm-start bench-labelling bench-iteration-growth bench-deflation-probe speed-accuracy clean

figures: build
	$(BIN) run --profile $(PROFILE) --jobs $(JOBS)

build:
	cargo build --release --locked

test:
	cargo fmt --all --check
	bash scripts/same-features.sh
	cargo clippy --locked --workspace --all-targets -- -D warnings
	cargo test --locked -p wearcoef-core
	cargo test --locked --release --workspace -- --include-ignored
	$(MAKE) test-client
	$(MAKE) test-measured
	$(MAKE) test-python
	$(MAKE) test-report
	$(MAKE) test-slurm

# Real client: the quick profile end to end, every artifact opened with pandas, numpy, Pillow.
test-client: build
	bash tests/client/run.sh

# Measured surfaces against SurfaceTopography and ContactMechanics, the tail tests against
# powerlaw (PyPI, venv installed if missing): readers, preparation, the non-periodic solve.
test-measured: build
	bash tests/measured/run.sh

# The Python package: crates/python built into a wheel by pip (maturin), installed in a fresh
# venv and checked against the binary bit for bit; then beside SurfaceTopography on real
# instrument files, and the worked example (examples/python_wear.py).
test-python: build
	bash tests/python/run.sh

# The committed report figures/default/index.html in headless Chromium (installed if missing):
# every image decodes; a copy with a truncated image must fail.
test-report:
	bash tests/report/run.sh

# A one-node Slurm cluster on this machine (installed if missing): the quick profile through
# `wearcoef submit`, byte-identical to a local run, also after a cancelled task.
test-slurm: build
	bash tests/slurm/run.sh

# The same cluster to try `wearcoef submit` by hand (docs/CLUSTER.md); state in SLURM_DIR.
SLURM_DIR ?= /var/tmp/wearcoef-slurm
slurm-start:
	@bash scripts/slurm-local.sh start $(SLURM_DIR)

slurm-stop:
	bash scripts/slurm-local.sh stop $(SLURM_DIR)

fmt:
	cargo fmt --all

# docs/BENCHMARKS.md from the dated runs under docs/benchmarks/ (scripts/benchmarks.py).
benchmarks:
	python3 scripts/benchmarks.py

bench: bench-fft bench-solver bench-peers bench-iteration bench-iteration-growth bench-deflation-probe bench-warm-start bench-labelling speed-accuracy

bench-fft:
	bash benches/fft_compare.sh

bench-solver:
	cargo bench --bench solver -- --noplot

# One solver iteration in units of one FFT pair of our own, drift-cancelling.
bench-iteration:
	cargo bench --bench iteration_cost

# Warm starts of a load sweep compared: scaled (the default), cold, extrapolated, and nested
# (the load solved on the grid of n/2 first).
bench-warm-start:
	cargo bench --bench warm_start -- 2 256 512 1024

# Iterations per load of the paper's 30-load sweep on the λl/λs = 128 spectrum against the
# box size (L/λl = 1 and 2 by default; BOXES="1 2 4" adds 4096²).
BOXES ?= 1 2
bench-iteration-growth:
	bash benches/iteration_growth.sh $(BOXES)

# Conjugate-gradient iterations on a fixed contact set against the box, with the solver's
# preconditioner alone, deflated by block indicators, and split orthogonally (numpy probe).
bench-deflation-probe:
	cargo build --release --locked --quiet
	"$$(bash benches/venv.sh numpy scipy)" benches/deflation_probe.py $(BIN) \
	  $(CARGO_TARGET_DIR)/deflation-probe $(BOXES)

# Periodic cluster labelling of wearcoef and scipy.ndimage.label on the same maps.
bench-labelling:
	bash benches/labelling_compare.sh

# Speed against accuracy: solver tolerance (with Tamaas from PyPI as peer), discretisation
# and realizations (figures/speed_accuracy.*); prints the tolerance it chooses per family.
speed-accuracy:
	WEARCOEF_PEERS_PYTHON="$$(bash benches/peers/venv.sh)" cargo bench --bench speed_accuracy

# Contact sweeps of wearcoef and Tamaas (PyPI) on the same surfaces, in the same run.
bench-peers:
	bash benches/peers/run.sh 256 512 1024

# Pressure ceiling against Tamaas's KatoSaturated: N, hardness (units of W/W0), loads.
bench-plastic:
	bash benches/peers/plastic.sh 512 0.25 0.01,0.03,0.05

# Removes the store data/ only if it holds nothing but a store (wearcoef clean refuses
# anything else and says what it would remove with --dry-run).
clean: build
	if [ -d data ]; then $(BIN) clean --data data; fi
