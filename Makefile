# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# the test suite's pytest-xdist workers (whole test files each: tests/study/test_slurm.py's SLURM serves its file);
# `make test TEST_WORKERS=0` runs it in one process
TEST_WORKERS ?= 2

.PHONY: demo test venv clean bench clean-cache smoke study-figures

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python setup.cfg pyproject.toml
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

# (no `fvdem compile` first: measured beside the campaign on a fresh clone, 2026-12-06, it saved 42 s of CPU and
# no wall time, 1,912 s against 1,893 s: the two workers seldom need the same kernel at the same moment, and the
# compile first leaves one core idle; docs/benchmarks.md)
test: $(STAMP)
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile

demo: $(STAMP)
	$(BIN)/fvdem run cases/demo.toml --out demo_out --overwrite
	$(BIN)/fvdem report demo_out
	@echo "demo written to demo_out/: timeseries.png, colours.png, mixing.png, gas_profile.png, void_fraction.png;"
	@echo "open demo_out/particles.pvd and demo_out/gas.pvd in ParaView"

# the paper's figures (Figs. 2, 3, 4, 7, 9 of seed 000, and the bed expansion) that docs/validation.md shows,
# drawn from the study's committed archive (docs/data/mema2020) in a scratch copy of it; run after each --archive
# of the campaign
STUDY_FIGURES := mixing_ar1 mixing_ar4_mp mixing_ar4_sp mixing_ar4_mp_drag fig3_mixing t95 \
                 fig7_void_fraction fig9_mixing bed_expansion
study-figures: $(STAMP)
	rm -rf $(VENV)/study-figures && cp -r docs/data/mema2020 $(VENV)/study-figures
	$(BIN)/fvdem study $(VENV)/study-figures --report > /dev/null
	mkdir -p docs/img/mema2020
	for f in $(STUDY_FIGURES); do cp $(VENV)/study-figures/$$f.png docs/img/mema2020/; done
	rm -rf $(VENV)/study-figures
	@echo "docs/img/mema2020/: $(STUDY_FIGURES) (.png)"

bench: $(STAMP)
	$(BIN)/python tools/bench_dem.py --json

clean:
	rm -rf $(VENV) build *.egg-info demo_out smoke_out

clean-cache:  # numba caches are invalidated only by edits to a kernel's own file; the law loops' modules too
	find fvdem -name '*.nbi' -delete -o -name '*.nbc' -delete
	rm -rf "$${XDG_CACHE_HOME:-$$HOME/.cache}/fvdem/law_loops" $${NUMBA_CACHE_DIR:+"$$NUMBA_CACHE_DIR/fvdem_law_loops"}

smoke: $(STAMP)  # the validation tools' quick modes (CI runs them after the tests)
	mkdir -p smoke_out
	$(BIN)/python tools/stability_map.py --quick --json --out smoke_out
	$(BIN)/python tools/speed_accuracy.py --quick --json --out smoke_out
	$(BIN)/python tools/validate_hindered_settling.py --quick --aspect-ratio 2 --ga-e 1296 --json --out smoke_out
	rm -rf smoke_out/study
	$(BIN)/fvdem study studies/smoke.toml --out smoke_out/study --json
