# Two entry points (see README): `make run` and `make test`.
# Both create .venv once and reuse it; the stamp file re-installs only when pyproject.toml changes.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-rllib train-rllib bench results clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[all]"
	touch $(STAMP)

RG := $(VENV)/bin/roller-gym

run: $(STAMP)  ## train the default agent (SAC, rl-zoo3) on the default task, evaluate it against LQR
	$(RG) train --algo sac --env roller_gym/RollerStabilize-v1 --log-folder runs
	$(RG) evaluate --env roller_gym/RollerStabilize-v1 --runs runs --algos sac --out results

TASKS := roller_gym/RollerStabilize-v1 roller_gym/RollerHold-v1 roller_gym/RollerBalance-v1 \
	roller_gym/RollerTrack-v0
results: $(STAMP)  ## train SAC, TD3 and PPO on every task, evaluate all, write docs/RESULTS.md
	set -e; for env in $(TASKS); do for algo in sac td3 ppo; do \
		$(RG) train --algo $$algo --env $$env --log-folder runs; done; done
	$(RG) evaluate --env $(TASKS) --runs runs --out docs/results \
		--report docs/RESULTS.md --notes docs/results/notes.md

test: $(STAMP)  ## the whole test suite and the linter
	$(PY) -m ruff check .
	$(PY) -m pytest -q

# Ray RLlib pins its own Gymnasium release (1.2.2): a second environment, .venv-rllib.
RLLIB_VENV := .venv-rllib
RLLIB_STAMP := $(RLLIB_VENV)/.installed

$(RLLIB_STAMP): pyproject.toml
	$(PYTHON) -m venv $(RLLIB_VENV)
	$(RLLIB_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(RLLIB_VENV)/bin/python -m pip install --quiet -e ".[train,render,dev,rllib]"
	touch $(RLLIB_STAMP)

# The environments' tests on RLlib's Gymnasium release (the physics knows no Gymnasium: its
# tests run once, in `make test`), and the RLlib training test.
RLLIB_TESTS := test_envs test_vector_env test_autoreset test_tasks test_rewards \
	test_reliability test_rendering test_sb3_vec_env test_layout test_rllib
test-rllib: $(RLLIB_STAMP)  ## the environment tests on RLlib's Gymnasium release, and the RLlib test
	$(RLLIB_VENV)/bin/python -m pytest -q $(RLLIB_TESTS:%=tests/%.py)

train-rllib: $(RLLIB_STAMP)  ## PPO on a local Ray
	$(RLLIB_VENV)/bin/roller-gym train-rllib

bench: $(STAMP)  ## measure the work-precision study: docs/benchmarks/workprecision.json, docs/BENCHMARKS.md
	$(RG) benchmark

clean:
	rm -rf $(VENV) $(RLLIB_VENV) runs results
