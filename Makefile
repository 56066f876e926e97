# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
# Both create .venv if missing and install torch first, pinned, so that a local CPU build is
# used where one exists instead of several GB of CUDA wheels.
VENV   ?= .venv
PY     := $(VENV)/bin/python
SB     := $(VENV)/bin/suctionbench
STAMP  := $(VENV)/.installed
TORCH  := torch==2.13.0

.PHONY: install demo test test-all lint bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q $(TORCH)
	$(PY) -m pip install -q -e ".[dev,ray]"
	touch $(STAMP)

# The main job: a short benchmark run of the GQ-CNN policy with the shipped model.
demo: $(STAMP)
	$(SB) eval --policy gqcnn --task smoke --seed 0 --out out/demo

test: $(STAMP)
	$(PY) -m pytest -q -m "not slow"

test-all: $(STAMP)
	$(PY) -m pytest -q

lint: $(STAMP)
	$(VENV)/bin/ruff check suctionbench tests

bench: $(STAMP)
	$(SB) bench label

clean:
	rm -rf $(VENV) out .pytest_cache
