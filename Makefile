# Touchline: `make run` starts the station on the built-in simulator; `make test` runs every test.
# Both install whatever is missing first (uv and Python deps, npm deps, protobuf code, frontend).
SHELL := /bin/bash
PY := .venv/bin/python
UV := python3 -m uv
SIM ?= builtin
PORT ?= 8000
RUN_ARGS ?=
# make run LOG=path/to/file.log[.gz]: replay a log instead of live input
LOG ?=
# make run TEAM=path/to/folder: the team's own plays, processors and libraries (default team/)
TEAM ?=
MINUTES ?= 3

.PHONY: run test setup proto contract build multicast chromium octave lint typecheck test-py test-ts \
        test-e2e bench soak experiments clean match fuzz evaluate

run: build multicast
	$(PY) -m launcher --sim $(SIM) --port $(PORT) $(if $(LOG),--log "$(LOG)") \
	  $(if $(TEAM),--team-dir "$(TEAM)") $(RUN_ARGS)

test: build multicast chromium octave lint typecheck test-py test-ts test-e2e
	@scripts/test-summary.sh

setup: .venv/.ok node_modules/.ok sslpb/__init__.py

.venv/.ok: pyproject.toml uv.lock
	@python3 -m uv --version >/dev/null 2>&1 || python3 -m pip install --quiet uv \
	  || python3 -m pip install --quiet --user uv \
	  || python3 -m pip install --quiet --break-system-packages uv
	$(UV) sync --frozen --python python3.11
	@touch $@

node_modules/.ok: package.json package-lock.json
	PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund
	@touch $@

sslpb/__init__.py: .venv/.ok node_modules/.ok $(wildcard proto/sslpb/*.proto) scripts/gen_proto.py
	TOUCHLINE_REQUIRE_TS_PROTO=1 $(PY) scripts/gen_proto.py

proto: .venv/.ok node_modules/.ok
	TOUCHLINE_REQUIRE_TS_PROTO=1 $(PY) scripts/gen_proto.py

# The browser contract: TypeScript types and the docs/api.md reference from backend/contract.py;
# and docs/team-api.md, the team-code interface, from the touchline package.
contract: .venv/.ok
	$(PY) scripts/gen_contract.py
	$(PY) scripts/gen_team_api.py

build: setup
	npm run build

multicast: .venv/.ok
	@scripts/setup-multicast.sh $(PY)

chromium:
	@scripts/ensure-chromium.sh

octave:
	@scripts/ensure-octave.sh

lint: setup
	$(PY) -m ruff check .

typecheck: setup
	$(PY) -m mypy
	npm run typecheck

test-py: setup multicast octave
	$(PY) -m pytest -q

test-ts: setup
	npm run test:unit

test-e2e: build multicast chromium
	npm run test:e2e

# Property tests with fresh random examples, ROUNDS times (make test runs them derandomized),
# then the real-process target: FUZZ_COUNT malformed datagrams into a launched station
# (scripts/fuzz_station.py, tests/fuzz/README.md).
ROUNDS ?= 10
FUZZ_COUNT ?= 1000000
FUZZ_ARGS ?=
fuzz: setup multicast
	for i in $$(seq $(ROUNDS)); do HYPOTHESIS_PROFILE=explore $(PY) -m pytest -q \
	  $$(grep -rl "from hypothesis" tests --include='test_*.py') || exit 1; done
	$(PY) scripts/fuzz_station.py --count $(FUZZ_COUNT) $(FUZZ_ARGS)

# Every benchmark; the full-scale loop last: the README's table (with the ratio to the floor)
bench: build multicast chromium
	for b in bench/*.py; do case $$b in bench/soak.py|bench/loop_bench.py) continue;; esac; \
	  echo "== $$b"; PYTHONPATH=. $(PY) $$b || exit 1; done
	@echo "== bench/loop_bench.py --browser (the README's table); load average: $$(cut -d' ' -f1-3 /proc/loadavg)"
	PYTHONPATH=. $(PY) bench/loop_bench.py --browser

# The station at full load for SOAK_MINUTES (issue 11: no loss over 10, memory flat over 30).
SOAK_MINUTES ?= 10
soak: setup multicast
	PYTHONPATH=. $(PY) bench/soak.py --minutes $(SOAK_MINUTES)

# The paper's experiments (filters, speed controllers), regenerated with fixed seeds.
experiments: setup multicast
	$(PY) -m experiments.filters.run --out docs/experiments/filters
	$(PY) -m experiments.controllers.run --out docs/experiments/controllers

# A whole 6 v 6 match on the built-in simulator, directed and judged; prints the result table.
match: build multicast
	$(PY) -m match --minutes $(MINUTES)

# Scenario suites, headless and in parallel (docs/evaluate.md): make evaluate SUITE=exercises
# PLAY=match OUT=folder (default var/reports/<date>-<time>-<suite>); TEAM=folder: team plays
# from there (e.g. TEAM=evaluate/solutions); more flags in EVAL_ARGS (python -m evaluate suite
# --help), e.g. EVAL_ARGS="--cluster tcp://host:8786"
SUITE ?= regression
PLAY ?=
OUT ?=
EVAL_ARGS ?=
evaluate: setup
	$(PY) -m evaluate suite $(SUITE) $(if $(PLAY),--play $(PLAY)) $(if $(OUT),--out "$(OUT)") \
	  $(if $(TEAM),--team-dir "$(TEAM)") $(EVAL_ARGS)

clean:
	rm -rf .venv node_modules sslpb frontend/src/gen frontend/dist test-results playwright-report
