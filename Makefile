# Two entry points (see README): `make run` and `make test`.
# Both create .venv once and reuse it; the stamp file re-installs only when pyproject.toml changes.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-rllib train-rllib bench throughput results results-train results-evaluate clean

# An index with torch's CPU build, where pip's own settings have none: on the open internet,
# `make test TORCH_INDEX=https://download.pytorch.org/whl/cpu` (torch==2.13.0 resolves to the
# CUDA build on PyPI, on Linux). Empty by default: an index pip cannot reach costs every
# install a time-out.
TORCH_INDEX ?=

# Every environment is made by one recipe in two steps: a venv in the stamp's folder with the
# third-party requirements of the extras the folder's stamps name (EXTRAS below), read from
# pyproject.toml without building the tree (so that it may run beside a build: .ci/run), then
# the project itself, editable.
%/.deps: pyproject.toml .ci/requirements.py
	$(PYTHON) -m venv $(@D)
	$(@D)/bin/python -m pip install --quiet --upgrade pip
	$(PYTHON) .ci/requirements.py $(EXTRAS) > $(@D)/requirements.txt
	$(@D)/bin/python -m pip install --quiet $(if $(TORCH_INDEX),--extra-index-url $(TORCH_INDEX)) -r $(@D)/requirements.txt
	touch $@

%/.installed: %/.deps
	$(@D)/bin/python -m pip install --quiet --no-deps -e .
	touch $@

$(VENV)/.deps $(STAMP): EXTRAS := all
# make keeps each step's stamp (a stamp made by a chain of pattern rules is otherwise deleted).
.PRECIOUS: %/.deps %/.installed

RG := $(VENV)/bin/roller-gym

run: $(STAMP)  ## train the default agent (SAC, rl-zoo3) on the default task, evaluate it against LQR
	$(RG) train --algo sac --env roller_gym/RollerStabilize-v2 --log-folder runs
	$(RG) evaluate --env roller_gym/RollerStabilize-v2 --runs runs --algos sac --out results

TASKS := roller_gym/RollerStabilize-v2 roller_gym/RollerHold-v2 roller_gym/RollerBalance-v2 \
	roller_gym/RollerTrack-v1 roller_gym/RollerSwing-v1 roller_gym/RollerHoldRandomized-v2 \
	roller_gym/RollerBalanceWeak-v0
SEEDS := 0 1 2 3 4
ALGOS := sac td3 ppo
# Options of roller-gym train for every run: `make results SEEDS="0 1" TASKS="roller_gym/RollerHold-v2"
# TRAIN_ARGS="--steps 2000" RESULTS_OUT=/tmp/smoke RESULTS_PAGE=/tmp/smoke/RESULTS.md` is a
# smoke run of the whole pipeline in minutes.
TRAIN_ARGS ?=
# Where the task files (<RESULTS_OUT>/tasks/<task>.json), the summary and the figures go, and
# the page rendered from every task file there.
RESULTS_OUT ?= docs/results
RESULTS_PAGE ?= docs/RESULTS.md
# One training ($$0: the algorithm, $$1: the seed, $$2: the task) afresh, into
# runs/results/<task>/seed<S>/<algo>.
TRAIN_ONE = dir=runs/results/$${2\#*/}/seed$$1; rm -rf $$dir/$$0; \
	$(RG) train --algo $$0 --env $$2 --seed $$1 --log-folder $$dir \
	--verbose 0 --checkpoints 0 $(TRAIN_ARGS)
# A round in pieces, each well inside two hours on two cores: `make results-train TASKS=<task>
# ALGOS=sac SEEDS="0 1 2"`, … (each piece adds its wall time to runs/results/<task>/wall_s),
# then `make results-evaluate TASKS=<task>` over every run there. `make results` does both, afresh.
# One algorithm retrained on its own: `make results-train results-evaluate TASKS=<task> ALGOS=td3
# RESULTS_ARGS=--keep-stored` keeps the other algorithms' runs from the task's stored file.
RESULTS_ARGS ?=
results-train: $(STAMP)  ## train ALGOS x SEEDS on each of TASKS (two at a time, in ALGOS' order), keeping other runs
	for env in $(TASKS); do runs=runs/results/$${env#*/}; mkdir -p $$runs; start=$$(date +%s); \
	for algo in $(ALGOS); do for seed in $(SEEDS); do echo $$algo $$seed $$env; done; done \
	| xargs -P 2 -L 1 sh -c '$(TRAIN_ONE)' || exit 1; \
	echo $$(( $$(date +%s) - start )) >> $$runs/wall_s; done
results-evaluate: $(STAMP)  ## evaluate every run of each of TASKS, write its task file and the page
	for env in $(TASKS); do runs=runs/results/$${env#*/}; \
	$(RG) results --runs $$runs --env $$env --algos $(ALGOS) --out $(RESULTS_OUT) \
	--report $(RESULTS_PAGE) $(RESULTS_ARGS) \
	--train-wall-s $$(awk '{s += $$1} END {print s + 0}' $$runs/wall_s) || exit 1; done
results: $(STAMP)  ## train SAC, TD3 and PPO with 5 seeds on each of TASKS afresh, evaluate, write docs/RESULTS.md
	for env in $(TASKS); do rm -rf runs/results/$${env#*/}; \
	$(MAKE) --no-print-directory results-train results-evaluate TASKS=$$env || exit 1; done

# The suite runs on every core (pytest-xdist), one test file per worker at a time, so that a
# file's module-scoped references are computed once.
PYTEST := -m pytest -q -n auto --dist loadfile
test: $(STAMP)  ## the whole test suite and the linter
	$(PY) -m ruff check .
	$(PY) $(PYTEST)

# Ray RLlib pins its own Gymnasium release (1.2.2): a second environment, .venv-rllib.
RLLIB_VENV := .venv-rllib
RLLIB_STAMP := $(RLLIB_VENV)/.installed

$(RLLIB_VENV)/.deps $(RLLIB_STAMP): EXTRAS := train,render,dev,rllib

# The tests of the environments' Gymnasium API on RLlib's Gymnasium release (the physics and
# the tasks know no Gymnasium: their tests run once, in `make test`), and the RLlib training
# test.
RLLIB_TESTS := test_envs test_env_episodes test_rllib
test-rllib: $(RLLIB_STAMP)  ## the environment tests on RLlib's Gymnasium release, and the RLlib test
	$(RLLIB_VENV)/bin/python $(PYTEST) $(RLLIB_TESTS:%=tests/%.py)

train-rllib: $(RLLIB_STAMP)  ## PPO on a local Ray
	$(RLLIB_VENV)/bin/roller-gym train-rllib

# The throughput page with its optional peers (EnvPool, Gymnasium's JAX Pendulum), in their
# own environment: jax is large and not needed by anything else.
PEERS_VENV := .venv-peers
PEERS_STAMP := $(PEERS_VENV)/.installed

$(PEERS_VENV)/.deps $(PEERS_STAMP): EXTRAS := peers

throughput: $(PEERS_STAMP)  ## measure docs/THROUGHPUT.md against CartPole, Pendulum, EnvPool and JAX
	$(PEERS_VENV)/bin/python -m roller_gym.bench.throughput measure --out docs

bench: $(STAMP)  ## measure the work-precision study: docs/benchmarks/workprecision.json, docs/BENCHMARKS.md
	$(RG) benchmark

clean:
	rm -rf $(VENV) $(RLLIB_VENV) $(PEERS_VENV) runs results
