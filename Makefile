# Two entry points, as the README says:
#   make demo   set up .venv and run the main job (no hardware needed)
#   make test   set up .venv and run the test suite
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean services

# '.[test]' brings the optional extras the tests exercise: line, learned and accel (torch==2.13.0, kornia).
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/tactip inspect --sim

# On every core (pytest-xdist; at most 4 workers): the simulated station the tests share is built once.
test: $(STAMP) services
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4

# The real services some tests use: PostgreSQL (the tests make throwaway clusters of their own on a
# local socket) and headless Chromium (the dashboard's browser test; Playwright drives it over its own
# protocol, so no chromedriver). Installed from Debian's packages when missing (as root); otherwise
# their tests skip and say why. Idempotent, quiet.
services:
	@missing=""; \
	ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1 || missing="$$missing postgresql"; \
	command -v chromium >/dev/null 2>&1 || missing="$$missing chromium"; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "make services: installing$$missing (apt-get)"; \
	    export DEBIAN_FRONTEND=noninteractive; \
	    apt-get install -y -qq -o DPkg::Lock::Timeout=300 --no-install-recommends $$missing >/dev/null 2>&1 || \
	    { apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq -o DPkg::Lock::Timeout=300 --no-install-recommends $$missing >/dev/null 2>&1; } || \
	    echo "make services: could not install$$missing; the tests that need them will be skipped"; \
	  else \
	    echo "make services:$$missing missing and not root: the tests that need them will be skipped"; \
	  fi; \
	fi

bench: $(STAMP)
	for script in bench/*.py; do $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info
