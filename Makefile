# The course's two commands: `make book` and `make test`. Everything else is a helper.
SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
VENV ?= .venv
PY := $(VENV)/bin/python
PROFILE ?= full
unexport MPLBACKEND  # kernels must use the inline backend, or notebooks lose their figures

.PHONY: book book-cache test install data lint sync lab bench clean

# torch's CPU build: requirements.txt pins the release, and on Linux PyPI's build of it is the CUDA one
# (several GB). The PyTorch CPU index has the same release for the CPU alone (an extra index: where it
# is unreachable pip says so, retries, and takes the release from its other sources). A CUDA build:
# `make install TORCH_INDEX=` (PyPI's), or any other PyTorch index (README, "Installing").
TORCH_INDEX ?= https://download.pytorch.org/whl/cpu
TORCH_PIN = $$(grep -m1 -E '^torch==' requirements.txt | cut -d'\#' -f1 | tr -d ' ')
# pip's own messages reach the terminal and a failed pip fails the target (pipefail); only the
# "WARNING: Location ... is ignored" lines of an absent local package folder are left out
QUIET_PIP = 2>&1 | { grep -v "^WARNING: Location" || true; }
# --no-compile: Python writes each module's bytecode the first time it is imported, for the modules
# the course uses, instead of pip compiling every file of every package (20 s of a fresh install)

$(VENV)/.installed: requirements.txt pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --no-compile --upgrade pip $(QUIET_PIP)
	$(PY) -m pip install --quiet --no-compile --no-deps $(if $(TORCH_INDEX),--extra-index-url $(TORCH_INDEX)) \
		"$(TORCH_PIN)" $(QUIET_PIP)  # its dependencies come with requirements.txt, from PyPI
	$(PY) -m pip install --quiet --no-compile -r requirements.txt $(QUIET_PIP)
	$(PY) -m pip install --quiet --no-compile --no-deps -e . $(QUIET_PIP)
	$(PY) -c "import husky_course, torch, pybullet, jupyter_book, nbval, xdist, jupytext, jupyterlab, playwright, ray"  # fail loudly if incomplete
	$(PY) -m ipykernel install --sys-prefix --name python3 >/dev/null
	@# JupyterLab for students: start the notebook's kernel without asking, no news pop-up
	mkdir -p $(VENV)/share/jupyter/lab/settings
	echo '{"@jupyterlab/notebook-extension:tracker": {"autoStartDefaultKernel": true},' \
		'"@jupyterlab/apputils-extension:notification": {"fetchNews": "false"}}' \
		> $(VENV)/share/jupyter/lab/settings/overrides.json
	touch $@

install: $(VENV)/.installed

data: install  ## build the dataset and train the models the chapters need, once, with progress bars
	$(PY) -m husky_course collect --profile $(PROFILE) --workers 2 > /dev/null
	$(PY) -m husky_course train all --profile $(PROFILE) > /dev/null
	$(PY) -m husky_course train memory --world moving --profile $(PROFILE) > /dev/null
	$(PY) -m husky_course train discs --sensing realistic --profile $(PROFILE) > /dev/null

book: data  ## execute every chapter (full profile by default) and build the HTML book
	@$(MAKE) --no-print-directory book-cache
	HUSKY_PROFILE=$(PROFILE) HUSKY_STATIC_WIDGETS=1 $(VENV)/bin/jupyter-book build . -W -n --keep-going
	@echo "The book is at $(CURDIR)/_build/html/index.html"

# jupyter-book's execution cache knows the notebooks' code, neither HUSKY_PROFILE nor the library's:
# `make book` drops it (and the pages built from it) when the profile or the library's code changed
# since the last build (`python -m husky_course fingerprint`: docstrings and comments left out, so
# editing one re-executes nothing). tests/test_fingerprints.py runs this target in a scratch folder.
LIBRARY_FINGERPRINT ?= $(PY) -m husky_course fingerprint
book-cache:
	@lib=$$($(LIBRARY_FINGERPRINT)); why=; \
	if [ -f _build/.profile ] && [ "$$(cat _build/.profile)" != "$(PROFILE)" ]; then \
		why="profile changed to $(PROFILE)"; \
	elif [ -d _build/.jupyter_cache ] && [ "$$(cat _build/.library 2>/dev/null || true)" != "$$lib" ]; then \
		why="the library's code changed"; fi; \
	if [ -n "$$why" ]; then echo "$$why: clearing the execution cache and the built pages"; \
		rm -rf _build/.jupyter_cache _build/.doctrees _build/html _build/jupyter_execute; fi; \
	mkdir -p _build && echo "$(PROFILE)" > _build/.profile && echo "$$lib" > _build/.library

lint: install
	$(VENV)/bin/ruff check husky_course tests benchmarks chapters conftest.py

lab: install  ## the chapters in JupyterLab, in the profile the book was last built with (else quick)
	HUSKY_PROFILE=$$(cat _build/.profile 2>/dev/null || echo quick) $(VENV)/bin/jupyter lab notebooks/ \
		$$([ "$$(id -u)" = 0 ] && echo --allow-root)

sync: install  ## after editing a chapter source (or its notebook outside Jupyter): update the other side
	$(VENV)/bin/jupytext --sync chapters/*.py

# Every chapter runs once here. nbval runs the notebooks first, in the book's mode (--keep-executed:
# HUSKY_STATIC_WIDGETS=1 for its kernels only) and keeps each chapter that passed, outputs included,
# in _build/executed/; tests/test_browser.py, run after them, builds the book from those without
# executing again. A student's live widgets have their own tests: test_jupyterlab.py (chapter 1 in
# JupyterLab's UI) and test_widgets_live.py (every widget of the library, live). Root conftest.py,
# tests/executed_book.py. The run is spread over two processes, one per core (pytest-xdist; --dist
# loadfile, scopes from conftest.py: a file's tests stay in one process, in order, and one process runs
# every chapter in order and then the browser test), each with one torch thread (OMP_NUM_THREADS=1:
# two processes of two threads each on two cores wait on each other); what a test checks does not
# depend on it.
TEST_JOBS ?= 2
test: install lint  ## unit tests + every notebook under nbval + the built book in a browser, quick profile
	$(PY) -m husky_course collect --profile quick --workers 2 --no-progress > /dev/null
	$(PY) -m husky_course train all --profile quick --no-progress > /dev/null
	$(PY) -m husky_course train memory --world moving --profile quick --no-progress > /dev/null
	$(PY) -m husky_course train discs --sensing realistic --profile quick --no-progress > /dev/null
	HUSKY_PROFILE=quick OMP_NUM_THREADS=1 $(PY) -m pytest notebooks tests --nbval-lax --keep-executed \
		-p no:cacheprovider -n $(TEST_JOBS) --dist loadfile --durations=15

bench: install  ## speeds measured side by side: collection, decisions, training (full profile)
	$(PY) benchmarks/bench_collection.py
	$(PY) benchmarks/bench_decision.py --profile $(PROFILE)
	$(PY) benchmarks/bench_planners.py
	$(PY) benchmarks/bench_training.py --profile $(PROFILE)
	$(PY) benchmarks/bench_pipeline.py --profile $(PROFILE)
	$(PY) benchmarks/bench_engines.py --profile $(PROFILE)
	$(PY) benchmarks/bench_threads.py --profile $(PROFILE)

clean:
	rm -rf _build
