# Every target bootstraps .venv on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench benchmark benchmark-wide benchmark-parity benchmark-quick sysdeps clean

$(STAMP): pyproject.toml
	@$(MAKE) --no-print-directory sysdeps
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

# Headless OpenGL on a CPU-only machine needs Mesa's EGL.
sysdeps:
	@if ! ldconfig -p | grep -q 'libEGL_mesa.so' ; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing Mesa EGL (libegl1 libegl-mesa0 libgl1-mesa-dri)"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null; \
	  else \
	    echo "Mesa EGL is missing: run 'sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri' and retry"; exit 1; \
	  fi; \
	fi

demo: $(STAMP)
	$(VENV)/bin/depthtrack demo --out demo-output

# -n auto: one pytest worker per core (pytest-xdist), whole files to each, so a file's
# module fixtures are made once: the suite is mostly single-threaded tracking on llvmpipe.
# --no-loadscope-reorder keeps tests/conftest.py's order, the slowest files first.
# --durations=25 prints the slowest tests, so a CI log says where the time went (and
# tests/conftest.py's SLOW_FILES can be kept up to date from it).
test: $(STAMP)
	$(PY) -m pytest -q -n auto --dist loadfile --no-loadscope-reorder --durations=25

bench: $(STAMP)
	$(VENV)/bin/depthtrack bench

# Synthetic ToF sequences from ../shared/data, all three trackers, and the likelihood comparison.
# The held-out benchmark (tools/benchmark.py): the dev split (tune on it) and the test
# split (report only), separately; benchmark-wide is every motion under one condition each
# (about 40 minutes per split), benchmark-quick the few-minute preset.
benchmark: $(STAMP)
	$(PY) tools/benchmark.py --split dev --out benchmark-output
	$(PY) tools/benchmark.py --split test --out benchmark-output

benchmark-wide: $(STAMP)
	$(PY) tools/benchmark.py --split dev --wide --out benchmark-output
	$(PY) tools/benchmark.py --split test --wide --out benchmark-output

# Cameras and azimuths compared, hc+ep against hc, and where the time goes (dev split).
benchmark-parity: $(STAMP)
	$(PY) tools/benchmark.py --split dev --parity --keep-tracks --out benchmark-output

benchmark-quick: $(STAMP)
	$(PY) tools/benchmark.py --split dev --quick --out benchmark-output
	$(PY) tools/benchmark.py --split test --quick --out benchmark-output

clean:
	rm -rf $(VENV) demo-output benchmark-output swim-report
