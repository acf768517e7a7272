# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test venv clean bench

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python setup.cfg pyproject.toml
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q

demo: $(STAMP)
	$(BIN)/fvdem run cases/demo.toml --out demo_out --overwrite
	@echo "demo written to demo_out/ (open demo_out/particles.pvd in ParaView)"

bench: $(STAMP)
	$(BIN)/python tools/bench_dem.py --json

clean:
	rm -rf $(VENV) build *.egg-info demo_out
