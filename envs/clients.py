"""What each RL client needs of the environments, written once: the autoreset mode of the
native vector environment and the form of the task ID.

:data:`CLIENTS` is the table the README's *Other clients* section shows (a test compares
them) and the interop tests use. A client that takes an ID string and builds the environments
in processes of its own needs ``"roller_gym:roller_gym/<Task>"`` (:func:`importing_id`,
Gymnasium's ``module:ID`` form): ``gymnasium.make`` then imports roller-gym, which registers
the tasks, in whatever process makes the environment, with no ``import roller_gym`` there.

A client whose wrapper accepts a mode silently and counts episodes wrong in it (skrl under
``next_step``) is recognized when it resets the vector environment (:func:`check_caller`, once
per environment: its code is on the call stack) and warned about.
"""

from __future__ import annotations

import sys
import warnings
from dataclasses import dataclass

from gymnasium.vector import AutoresetMode
from roller_gym.physics.scene import shown

__all__ = ["CLIENTS", "Client", "check_caller", "importing_id"]


def importing_id(env_id: str) -> str:
    """``env_id`` in Gymnasium's ``module:ID`` form (``"roller_gym:roller_gym/RollerHold-v2"``):
    ``gymnasium.make`` of it imports roller-gym first, in any process."""
    return env_id if ":" in env_id else f"roller_gym:{env_id}"


@dataclass(frozen=True)
class Client:
    """One RL client: the autoreset mode to give the native vector environment, why, and the
    modes its wrapper accepts without an error but counts wrong."""

    name: str
    package: str  #: its top-level import name
    autoreset_mode: AutoresetMode
    why: str
    miscounts: tuple[AutoresetMode, ...] = ()


CLIENTS: dict[str, Client] = {client.package: client for client in (
    Client("TorchRL", "torchrl", AutoresetMode.DISABLED,
           "TorchRL resets the ended sub-environments itself (reset_mask); it refuses "
           "next_step and prefers disabled to same_step"),
    Client("skrl", "skrl", AutoresetMode.SAME_STEP,
           "skrl's wrapper takes the observation a step returns as the next one, and never "
           "resets a vector environment after the first reset",
           miscounts=(AutoresetMode.NEXT_STEP,)),
    Client("CleanRL", "cleanrl", AutoresetMode.SAME_STEP,
           "CleanRL's scripts make SyncVectorEnv(..., autoreset_mode=SAME_STEP) and read "
           "info[\"final_info\"]"),
    Client("RLlib", "ray", AutoresetMode.NEXT_STEP,
           "RLlib's env runner makes the vector env itself, in Gymnasium's default mode, and "
           "reads the step after an episode's end as the next episode's reset"),
)}

#: How many frames above the environment's reset are searched for a client's code.
_DEPTH = 8


def check_caller(env: object, mode: AutoresetMode) -> None:
    """Warn (once per ``env``) if a client known to miscount ``mode`` is calling ``env``'s
    reset: its module is among the ``_DEPTH`` frames above the caller of this function."""
    if getattr(env, "_client_checked", False):
        return
    env._client_checked = True  # type: ignore[attr-defined]
    frame = sys._getframe(2)
    for _ in range(_DEPTH):
        if frame is None:
            return
        package = str(frame.f_globals.get("__name__", "")).partition(".")[0]
        client = CLIENTS.get(package)
        if client is not None:
            if mode in client.miscounts:
                warnings.warn(
                    f"{client.name} is stepping a roller-gym vector environment in "
                    f"autoreset_mode={shown(mode.name.lower())}, which it accepts but miscounts: "
                    f"{client.why}. Make it with gymnasium.make_vec(ID, num_envs=N, "
                    f"autoreset_mode={shown(client.autoreset_mode.name.lower())}).",
                    UserWarning, stacklevel=3)
            return
        frame = frame.f_back
