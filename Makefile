# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
# Both create .venv if missing and install torch first, pinned, so that a local CPU build is
# used where one exists instead of several GB of CUDA wheels. `make demo` installs only what the
# package needs; `make test` adds the dev tools and Ray (the `ray` extra, ~240 MB, for the Ray
# engine's tests).
VENV   ?= .venv
PY     := $(VENV)/bin/python
SB     := $(VENV)/bin/suctionbench
STAMP  := $(VENV)/.installed
DEVSTAMP := $(VENV)/.installed-dev
TORCH  := torch==2.13.0
DEMO   := out/demo

.PHONY: install demo test test-all lint bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q $(TORCH)
	$(PY) -m pip install -q -e .
	touch $(STAMP)

$(DEVSTAMP): $(STAMP)
	$(PY) -m pip install -q -e ".[dev,ray]"
	touch $(DEVSTAMP)

# The main job: a short benchmark run of the GQ-CNN policy with the shipped model, then its report.
demo: $(STAMP)
	$(SB) eval --policy gqcnn --task smoke --seed 0 --out $(DEMO) --overwrite
	$(SB) report $(DEMO) --out $(DEMO)/report > /dev/null
	@echo ""
	@echo "Report: $(DEMO)/report/index.html (and report.md), rebuilt from the run logs by"
	@echo "  $(SB) report $(DEMO) --out $(DEMO)/report"
	@echo "The CLI lives in $(VENV): run $(SB) --help, or first: source $(VENV)/bin/activate"

test: $(DEVSTAMP)
	$(PY) -m pytest -q -m "not slow"

test-all: $(DEVSTAMP)
	$(PY) -m pytest -q

lint: $(DEVSTAMP)
	$(VENV)/bin/ruff check suctionbench tests examples

bench: $(STAMP)
	$(SB) bench label

clean:
	rm -rf $(VENV) out .pytest_cache
