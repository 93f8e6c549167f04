# The two set-up commands of the README:
#   make report   -> fitted-model reports for the recordings in recordings/
#   make test     -> the test suite
# Both create ./.venv and install wheelsoil into it on first use.

PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
STAMP   = $(VENV)/.installed

.PHONY: report test bench vm-packages clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[test]"
	touch $(STAMP)

report: $(STAMP)
	@for rec in recordings/*.mcap; do \
	  name=$$(basename $$rec .mcap); \
	  terrain=$${name%%-*}; \
	  echo "== $$rec (terrain $$terrain) -> reports/$$name/"; \
	  $(BIN)/wheelsoil fit $$rec --terrain $$terrain -o reports/$$name || exit 1; \
	done

test: $(STAMP)
	$(BIN)/python -m pytest -q -ra -n auto --dist loadfile

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

# Packages for the real-vcan0 VM tests (tests skip with the reason without them).
vm-packages:
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
	  qemu-system-x86 linux-image-amd64 busybox-static can-utils

clean:
	rm -rf $(VENV) reports
