# Two commands do all the set-up on a fresh machine (python3 >= 3.10 with venv, and make):
#   make demo   - the main job: the demo against the built-in simulator
#   make test   - ruff, mypy --strict, the strict docs build and the tests (what .ci/run calls)
VENV ?= .venv
PYTHON ?= python3
BIN := $(VENV)/bin
EXTRAS := test,bench,mavlink,web,docs,capture
STAMP := $(VENV)/.installed-stamp

# `make test` lints and builds the docs once, then runs the suite on every CPython in
# PYTHONS it finds (pyenv's versions, or python3.X on PATH; .ci/pythons.py) and prints which
# ran and which were missing. $(VENV) (made with $(PYTHON)) runs it at full size; every other
# version runs in its own .venv-3.X with GCU_TEST_SIZE=reduced (set per run by the script):
# the generated heavy tests shrink (the session contract from 100,000 to 10,000 commands,
# Hypothesis to 25 examples a test, ...; tests/_scale.py), so each CI run has exactly one
# full-size run, and `make test` on a fresh clone with all four took 36.5 minutes on a
# shared 2-core VM (10.5 min full, ~8 min per reduced run: most of the suite is real-time
# waiting on sockets, subprocesses and the browser, which the reduced size does not shrink).
# `make test PYTHONS=` runs the main venv only.
PYTHONS ?= 3.10 3.11 3.12 3.13
TEST_EXTRAS := test,bench,mavlink,web,capture

.PHONY: demo test lint docs browser tshark iproute2 bench clean

$(STAMP): pyproject.toml src/gcu_async/__init__.py
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$(EXTRAS)]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/gcu-async demo

lint: $(STAMP)
	$(BIN)/ruff check src tests examples benchmarks tools .ci
	$(BIN)/mypy

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet --site-dir $(CURDIR)/site

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

# The network-topology tests (tests/test_netns_*.py) build two hosts in network namespaces
# with iproute2's `ip`, as root. In CI (CI=true, root, apt available) it is installed when
# missing; elsewhere, or without root, those tests skip and say why.
iproute2:
	@if ! command -v ip >/dev/null && [ "$${CI:-}" = "true" ] && [ "$$(id -u)" = 0 ] \
	    && command -v apt-get >/dev/null; then \
	  echo "installing iproute2 for the network-namespace tests"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq iproute2 \
	    >/dev/null) || echo "iproute2 could not be installed: the netns tests will skip"; \
	fi

test: lint docs browser tshark iproute2
	$(BIN)/python .ci/pythons.py --main-venv $(VENV) --versions "$(PYTHONS)" --extras $(TEST_EXTRAS)

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_codec.py
	$(BIN)/python benchmarks/bench_client.py

clean:
	rm -rf $(VENV) $(VENV)-3.* site .pytest_cache .mypy_cache .ruff_cache .hypothesis
