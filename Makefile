# The two commands: `make demo` (set up, then run the main job on small defaults) and `make test`.
VENV ?= .venv
PY := $(VENV)/bin/python
export MPLBACKEND := Agg

.PHONY: setup demo test test-slow bench clean-venv

setup:
	@bash scripts/ensure_system_libs.sh
	@VENV=$(VENV) bash scripts/make_venv.sh

demo: setup
	$(VENV)/bin/sortbot demo --out outputs/demo

test: setup
	$(PY) -m pytest -q

test-slow: setup
	$(PY) -m pytest -q -m slow

bench: setup
	$(VENV)/bin/sortbot bench sim

clean-venv:
	rm -rf $(VENV)
