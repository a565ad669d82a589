# Two entry points (see README): `make run` and `make test`.
# Both create .venv once and reuse it; the stamp file re-installs only when pyproject.toml changes.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test lint bench results clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[all]"
	touch $(STAMP)

run: $(STAMP)  ## train the default agent on the default task, evaluate it, write results/
	$(PY) scripts/train.py
	$(PY) scripts/evaluate.py --env RollerStabilize-v0 --models runs/sac-RollerStabilize-v0 --out results

TASKS := RollerStabilize-v0 RollerHold-v0 RollerBalance-v0
results: $(STAMP)  ## train SAC, TD3 and PPO on every task, evaluate all, write docs/RESULTS.md
	set -e; for env in $(TASKS); do for algo in sac td3 ppo; do \
		$(PY) scripts/train.py --algo $$algo --env $$env; done; done
	$(PY) scripts/evaluate.py --env $(TASKS) --runs runs --out docs/results \
		--report docs/RESULTS.md --notes docs/results/notes.md

test: $(STAMP)  ## the whole test suite and the linter
	$(PY) -m ruff check .
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) scripts/benchmark.py

clean:
	rm -rf $(VENV) runs results
