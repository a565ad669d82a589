"""The per-step outcome record, declared once: what the outcome kernel reads and writes.

* **Inputs**: the integrator's :data:`STEP_FIELDS` (a
  :class:`~roller_gym.physics.integrators.StepResult`'s rows) and the step's context
  (:data:`CONTEXT_FIELDS`, rows the environments keep).
* **The step quantities** a task's objective reads by name (:data:`QUANTITIES`, as a
  :class:`Step`): each an input row of the same name, or one of the two the kernel computes
  (``psi``, ``position_error``).
* **Outputs**: the reward, the termination flag, the info (:data:`INFO_KEYS`) and the
  observation. Each output is an input row of the same name passed on, or one of
  :data:`COMPUTED`, which the kernel computes.

Index constants, the kernel's scratch layout and the Python path derive from these
declarations: row ``name`` of a table is ``O.name`` (outputs), ``F.name`` (flags), ``S.name``
(the step's rows) or ``C.name`` (the context's), compile-time constants in the kernels.
Adding an info key that passes an input on is one line in :data:`INFO_KEYS`; adding a step
quantity is one line in :data:`QUANTITIES` (and its input row where it is a new one).
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Mapping
from typing import Any

import numpy as np
from roller_gym.physics.integrators import STEP_FIELDS

__all__ = ["COMPUTED", "CONTEXT_FIELDS", "FLAG_ROWS", "INFO_KEYS", "INFO_ROW", "OUTCOME_ROWS",
           "QUANTITIES", "STEP_FIELDS", "C", "F", "O", "S", "Step", "rows", "step_record"]

#: The info keys of every step and reset, with their types and units; grouped by type (the
#: floats, the integer, the flags), so that each type's keys are consecutive rows of the
#: outcome's table or flags, which the single environment reads in one pass.
INFO_KEYS: dict[str, tuple[type, str]] = {
    "phi": (float, "φ [rad]"),
    "phi_dot": (float, "φ' [rad/s]"),
    "psi": (float, "ψ [rad], where the roller is on the surface"),
    "torque": (float, "τ [N·m] applied over the step (0 at reset)"),
    "normal_force": (float, "N [N] at the end of the step (NaN where the step failed)"),
    "friction_force": (float, "F [N] at the end of the step (NaN where the step failed)"),
    "energy": (float, "E [J] at the end of the step (NaN where the step failed)"),
    "liftoff_margin": (float, "smallest N/(m g) during the step [-] (NaN: failed step)"),
    "slip_margin": (float, "smallest (μN − |F|)/(m g) during the step [-] (NaN: failed)"),
    "error_estimate": (float, "the integrator's estimate of the step's state error (inf: not "
                              "estimated, fixed-substep schemes and DOP853; 0 at reset)"),
    "target_phi": (float, "the target φ* [rad]"),
    "target_psi": (float, "the target ψ* [rad]"),
    "target_phi_dot": (float, "how fast the target moves, φ*' [rad/s] (0: a rest position)"),
    "target_torque": (float, "τ* [N·m], the torque that holds the roller at rest at φ*"),
    "position_error": (float, "the task's position error [rad of φ]"),
    "substeps": (int, "integrator substeps taken (0 at reset)"),
    "lifting": (bool, "the roller left the surface (N <= 0) during the step"),
    "slipping": (bool, "the friction needed exceeded μN during the step"),
    "nonfinite": (bool, "the step could not stay finite (or |φ| passed 2⁵⁰ rad, where "
                       "sines are NaN): the state is the one before it"),
    "tol_met": (bool, "the step met the integrator's tolerance (False: not verified: out "
                     "of reach of float64 or of the substeps a step may take, its error "
                     "estimate grew past it along the step, or reruns of a long step ended "
                     "too far from it)"),
    "is_success": (bool, "the task's success rule holds (see the task's docs), on a step "
                         "that did not end in lift-off, slip or a non-finite state"),
}

#: Per-roller numbers a step's outcome takes besides the integrator's, the environments' own
#: state (rows of the context table, in this order): name -> meaning [unit].
CONTEXT_FIELDS: dict[str, str] = {
    "torque": "τ [N·m] applied over the step (0 at a start)",
    "target_phi": "the target φ* [rad]",
    "target_phi_dot": "how fast the target moves, φ*' [rad/s]",
    "target_torque": "τ* [N·m], the torque that holds the roller at rest at φ*",
    "target_energy": "E* [J], the energy of resting at φ* (V = 0 at φ = 0)",
    "wrap_rate": "the rate q errors are wrapped by [-] (0: none; roller_gym.task.wrap_rate)",
    "psi_rate": "dψ/dφ [-] (roller_gym.task.psi_rate)",
}

#: The step quantities a task's objective reads (``s.<name>`` of a :class:`Step`): name ->
#: meaning [unit]. Each is an input row of the same name, except ``psi`` and
#: ``position_error``, which the kernel computes.
QUANTITIES: dict[str, str] = {
    "phi": "φ [rad] at the end of the step",
    "phi_dot": "φ' [rad/s] at the end of the step",
    "psi": "ψ = (dψ/dφ) φ [rad], where the roller is on the surface",
    "torque": "τ [N·m] applied over the step",
    "target_phi": "the target φ* [rad]",
    "target_phi_dot": "the target's rate φ*' [rad/s]",
    "target_torque": "τ* [N·m], the torque that holds the roller at rest at φ*",
    "target_energy": "E* [J], the energy of resting at φ*",
    "position_error": "the wrapped distance to the target [rad of φ] (roller_gym.task)",
    "energy": "E [J] at the end of the step (NaN where the step failed)",
    "normal_force": "N [N] at the end of the step (NaN where the step failed)",
    "friction_force": "F [N] at the end of the step (NaN where the step failed)",
    "liftoff_margin": "smallest N/(m g) during the step [-]",
    "slip_margin": "smallest (μN − |F|)/(m g) during the step [-]",
}
#: A step's quantities by name (floats in the kernel; floats or arrays in Python).
Step = namedtuple("Step", tuple(QUANTITIES))

#: The outputs the kernel computes (the others pass an input row of their name on).
COMPUTED = ("reward", "terminated", "psi", "lifting", "slipping", "nonfinite", "error_estimate",
            "target_psi", "position_error", "is_success")
#: The rows of the outcome's table (float64): the reward, then the info's float and integer
#: keys in INFO_KEYS order (integers as whole floats).
OUTCOME_ROWS = ("reward", *(key for key, (kind, _) in INFO_KEYS.items() if kind is not bool))
#: The rows of the outcome's flags (bool): terminated, then the info's boolean keys in
#: INFO_KEYS order. Written as booleans by the kernel: no conversion after it.
FLAG_ROWS = ("terminated", *(key for key, (kind, _) in INFO_KEYS.items() if kind is bool))


def rows(name: str, names: tuple[str, ...] | dict[str, Any]) -> Any:
    """A named tuple of the row numbers of ``names`` (``rows("O", OUTCOME_ROWS).reward``):
    read by name in the kernels, where it is a compile-time constant."""
    return namedtuple(name, tuple(names))(*range(len(names)))


S = rows("StepRows", STEP_FIELDS)
C = rows("ContextRows", CONTEXT_FIELDS)
O = rows("OutcomeRows", OUTCOME_ROWS)
F = rows("FlagRows", FLAG_ROWS)
#: Each info key's row: in the outcome's flags for a boolean key, else in its table.
INFO_ROW = {key: getattr(F if kind is bool else O, key) for key, (kind, _) in INFO_KEYS.items()}

_INPUTS = (*STEP_FIELDS, *CONTEXT_FIELDS)
_unsourced = [q for q in QUANTITIES if q not in _INPUTS and q not in COMPUTED]
_unwritten = [k for k in (*OUTCOME_ROWS, *FLAG_ROWS) if k not in _INPUTS and k not in COMPUTED]
if _unsourced or _unwritten:
    raise ImportError(f"the outcome record names quantities {_unsourced} and outputs "
                      f"{_unwritten} that are neither an input row nor computed (COMPUTED)")


def step_record(values: Mapping[str, Any]) -> Step:
    """A :class:`Step` from a mapping of quantities (e.g. a step's info); a quantity it lacks
    is NaN, so a formula that reads it gives NaN rather than a plausible number."""
    return Step(**{name: values.get(name, np.nan) for name in QUANTITIES})
