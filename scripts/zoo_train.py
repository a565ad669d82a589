"""rl-zoo3's training on the native batch: ``python -m roller_gym.scripts.zoo_train [OPTIONS]``.

The options are ``python -m rl_zoo3.train``'s, all of them, passed on as they are. rl-zoo3
builds its training and evaluation environments as ``DummyVecEnv`` (or ``SubprocVecEnv``) of
single environments; its hook for a vector env of one's own,
``ExperimentManager.default_vec_env_cls``, has no command-line option. This program sets it
to :func:`roller_gym.sb3.from_env_fns` (the native batch for a roller-gym task, DummyVecEnv
for any other) and runs rl-zoo3's train. ``roller-gym train`` runs it, and
``roller-gym train --show-command`` prints it, so the printed command trains as
``roller-gym train`` does; ``python -m rl_zoo3.train`` with the same options steps single
environments through DummyVecEnv instead.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

#: The module to run with ``python -m``.
MODULE = "roller_gym.scripts.zoo_train"


def train(zoo_argv: Sequence[str]) -> None:
    """Run ``rl_zoo3.train`` with the arguments ``zoo_argv``, its environments the native
    batch."""
    from rl_zoo3.exp_manager import ExperimentManager
    from rl_zoo3.train import train as zoo_train
    from roller_gym.sb3 import from_env_fns

    saved = sys.argv, ExperimentManager.default_vec_env_cls
    sys.argv = ["rl_zoo3.train", *zoo_argv]  # rl-zoo3 parses sys.argv
    ExperimentManager.default_vec_env_cls = staticmethod(from_env_fns)
    try:
        zoo_train()
    finally:
        sys.argv, ExperimentManager.default_vec_env_cls = saved


if __name__ == "__main__":
    train(sys.argv[1:])
