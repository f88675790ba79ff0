# Two commands do all the set-up on a fresh machine (python3 >= 3.10 with venv, and make):
#   make demo   - the main job: the demo against the built-in simulator
#   make test   - ruff, mypy --strict, the strict docs build and the tests (what .ci/run calls)
VENV ?= .venv
PYTHON ?= python3
BIN := $(VENV)/bin
EXTRAS := test,bench,mavlink,web,docs,capture
STAMP := $(VENV)/.installed-stamp

.PHONY: demo test lint docs browser tshark bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$(EXTRAS)]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/gcu-async demo

lint: $(STAMP)
	$(BIN)/ruff check src tests examples benchmarks tools
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

test: lint docs browser tshark
	$(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_codec.py
	$(BIN)/python benchmarks/bench_client.py

clean:
	rm -rf $(VENV) site .pytest_cache .mypy_cache .ruff_cache .hypothesis
