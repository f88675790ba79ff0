# Two commands do all the set-up on a fresh machine (python3 >= 3.10 with venv, and make):
#   make demo   - the main job: the demo against the built-in simulator
#   make test   - ruff, mypy --strict, the strict docs build and the tests (what .ci/run calls)
# and `make check` is the inner loop: ruff, mypy and the fast tier (CONTRIBUTING.md).
VENV ?= .venv
PYTHON ?= python3
BIN := $(VENV)/bin
# `make demo` installs the package alone; `make check` adds the user extras and what the
# inner loop runs (the `test` and `lint` dependency groups of pyproject.toml); `make test`
# adds the rest (the real parts of the full tier, the docs build). One venv serves all three,
# and none waits for, or fails on, a tool it does not run.
USER_EXTRAS := mavlink,web,capture
CHECK_GROUPS := --group test --group lint
DEV_GROUPS := --group dev
DOCS_GROUPS := --group docs
DEMO_STAMP := $(VENV)/.demo-stamp
DOCS_STAMP := $(VENV)/.docs-stamp
CHECK_STAMP := $(VENV)/.check-stamp
DEV_STAMP := $(VENV)/.installed-stamp
INPUTS := pyproject.toml src/gcu_async/__init__.py README.md  # README.md: the long description
# Compiled modules and pytest's rewritten test modules are cached in __pycache__ (ignored by
# git) even where the environment turns bytecode off: a second `make check` loads them
# instead of compiling ~400 modules again.
unexport PYTHONDONTWRITEBYTECODE

# `make test` lints and builds the docs once, then runs the suite on every CPython in PYTHONS
# it finds (pyenv's versions, or python3.X on PATH; .ci/pythons.py) and prints which ran and
# which were missing. $(VENV) (made with $(PYTHON)) runs every test at full size: the full
# tier (real time, processes, ...) with JOBS pytest-xdist workers while the fast tier
# (sans-I/O, in-memory, virtual time) runs in one process, then the tests marked `alone` one
# at a time. Every other version runs the fast tier in its own .venv-3.X at reduced size
# (tests/helpers/tiers.py, tests/helpers/scale.py). `make test PYTHONS=` runs the main venv only.
PYTHONS ?= 3.10 3.11 3.12 3.13
JOBS ?= 4

.PHONY: demo test check lint docs browser tshark iproute2 bench clean

$(DEMO_STAMP): $(INPUTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet -e .
	touch $(DEMO_STAMP)

# --group needs pip >= 25.1: upgraded first
$(CHECK_STAMP): $(INPUTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$(USER_EXTRAS)]' $(CHECK_GROUPS)
	touch $(CHECK_STAMP) $(DEMO_STAMP)

$(DEV_STAMP): $(INPUTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$(USER_EXTRAS)]' $(DEV_GROUPS)
	touch $(DEV_STAMP) $(CHECK_STAMP) $(DOCS_STAMP) $(DEMO_STAMP)

# `make docs` on its own installs the package and the `docs` group only (no test tools)
$(DOCS_STAMP): $(INPUTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e . $(DOCS_GROUPS)
	touch $(DOCS_STAMP) $(DEMO_STAMP)

demo: $(DEMO_STAMP)
	$(BIN)/gcu-async demo

lint: $(CHECK_STAMP)
	$(BIN)/ruff check src tests examples benchmarks tools .ci
	$(BIN)/mypy

docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --site-dir $(CURDIR)/site

# The web example's page is tested in Debian's Chromium when it is there. In CI (CI=true,
# root, apt available) it is installed; elsewhere the test skips and says why.
browser:
	@if [ ! -x /usr/bin/chromium ] && [ "$${CI:-}" = "true" ] && [ "$$(id -u)" = 0 ] \
	    && command -v apt-get >/dev/null; then \
	  echo "installing Debian's chromium for the browser test"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium \
	    >/dev/null) || echo "chromium could not be installed: the browser test will skip"; \
	fi

# The Wireshark dissector is tested with Debian's tshark (and tcpdump for captures made
# independently of the library). In CI (CI=true, root, apt available) they are installed;
# elsewhere those tests skip and say why.
tshark:
	@if { [ ! -x /usr/bin/tshark ] || [ ! -x /usr/bin/tcpdump ]; } && [ "$${CI:-}" = "true" ] \
	    && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "installing Debian's tshark and tcpdump for the Wireshark dissector tests"; \
	  echo "wireshark-common wireshark-common/install-setuid boolean false" \
	    | debconf-set-selections 2>/dev/null; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq tshark \
	    tcpdump >/dev/null) || echo "tshark could not be installed: the dissector tests will skip"; \
	fi

# The network-topology tests (tests/netns/test_netns_*.py) build two hosts in network namespaces
# with iproute2's `ip`, as root. In CI (CI=true, root, apt available) it is installed when
# missing; elsewhere, or without root, those tests skip and say why.
iproute2:
	@if ! command -v ip >/dev/null && [ "$${CI:-}" = "true" ] && [ "$$(id -u)" = 0 ] \
	    && command -v apt-get >/dev/null; then \
	  echo "installing iproute2 for the network-namespace tests"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq iproute2 \
	    >/dev/null) || echo "iproute2 could not be installed: the netns tests will skip"; \
	fi

test: $(DEV_STAMP) lint docs browser tshark iproute2
	$(BIN)/python .ci/pythons.py --main-venv $(VENV) --versions "$(PYTHONS)" \
	  --extras $(USER_EXTRAS) --groups test --jobs $(JOBS)

# The inner loop: lint and the fast tier at reduced size on the main venv, less the `heavy`
# session-contract shards (no docs build, no other interpreters, nothing real-time; `make
# test` runs all of it). CHECK_JOBS pytest-xdist workers: each collects the ~11,000 items
# itself, then they share the run.
CHECK_JOBS ?= 2
check: lint
	GCU_TEST_SIZE=reduced $(BIN)/python -m pytest -q -p no:cacheprovider -n $(CHECK_JOBS) \
	  -m "fast and not heavy"

bench: $(DEV_STAMP)
	$(BIN)/python benchmarks/bench_codec.py
	$(BIN)/python benchmarks/bench_client.py
	$(BIN)/python benchmarks/bench_conformance.py
	$(BIN)/python benchmarks/bench_capacity.py

clean:
	rm -rf $(VENV) $(VENV)-3.* site .pytest_cache .mypy_cache .ruff_cache .hypothesis
