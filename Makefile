# The two commands of the README. Both install what is missing first (scripts/bootstrap.sh).
#   make render   render scenes/default.yaml clean + 11 visibility levels into out/default
#   make test     run the test suite
VENV  := .venv
STAMP := $(VENV)/.seahaze-installed
OUT   ?= out/default

.PHONY: render test lint docs bench
render: $(STAMP)
	$(VENV)/bin/seahaze render scenes/default.yaml --vis 300..4000 --out $(OUT)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests scripts

docs: $(STAMP)
	$(VENV)/bin/python scripts/gen_scene_docs.py

bench: $(STAMP)
	$(VENV)/bin/python scripts/bench_passes.py

$(STAMP): pyproject.toml scripts/bootstrap.sh
	bash scripts/bootstrap.sh
