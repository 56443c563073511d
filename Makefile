# The two commands of the README. Both install what is missing first (scripts/bootstrap.sh).
#   make render   render scenes/default.yaml clean + 11 visibility levels into out/default
#   make test     run the test suite (two pytest-xdist workers: most of its time is LLVM compiling
#                 kernels on one thread, so a second worker overlaps it; 515 s for 2558 tests
#                 from a fresh clone with an empty kernel cache on a 2-vCPU machine, 775 s for
#                 2579 on a 1.5x slower one: scripts/bench_suite.py)
VENV  := .venv
STAMP := $(VENV)/.seahaze-installed
OUT   ?= out/default

.PHONY: render test lint docs bench
render: $(STAMP)
	$(VENV)/bin/seahaze render scenes/default.yaml --vis 300..4000 --out $(OUT)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q -n 2

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests scripts

docs: $(STAMP)
	$(VENV)/bin/python scripts/gen_scene_docs.py

bench: $(STAMP)
	$(VENV)/bin/python scripts/bench_passes.py

$(STAMP): pyproject.toml scripts/bootstrap.sh
	bash scripts/bootstrap.sh
