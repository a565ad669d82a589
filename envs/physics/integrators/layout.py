"""The kernels' record layout, declared once: the per-roller rows of a batch's ``io`` table
(:data:`ROWS`: the scene's :data:`SCENE_FIELDS`, the inputs :data:`INPUT_FIELDS`, what a
stepper carries :data:`CARRY_FIELDS`, the outcome :data:`STEP_FIELDS` of
:class:`StepResult`), their row numbers as constants for the kernels, a stepper's settings
:data:`CFG_FIELDS`, and the tables' memory (:func:`row_table`, :func:`scene_arrays`).

One column per roller, so a roller's numbers never depend on the other columns: its step is
bit for bit the same alone and in any batch.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, fields

import numpy as np
from roller_gym.physics.scene import Scene, shown

#: The per-roller scene numbers the kernels take, in the order of their rows.
SCENE_FIELDS = ("m", "r", "kappa", "e", "k", "g", "damping", "mu")
#: The per-roller inputs of a step: φ [rad], φ' [rad/s] at its start, τ [N·m].
INPUT_FIELDS = ("phi_in", "phi_dot_in", "tau")
#: What a stepper carries per roller from one step to the next: the substep size [s] the
#: controller proposed at the end of the last step, where the next one starts (0: none, the
#: first substep is predicted).
CARRY_FIELDS = ("h_next",)


@dataclass(frozen=True)
class StepResult:
    """The outcome of one control step, at its end unless said otherwise.

    Attributes:
        phi: φ [rad].
        phi_dot: φ' [rad/s].
        phi_ddot: φ'' [rad/s²] under the step's torque (NaN where not finite).
        substeps: accepted substeps (for ``"dop853"``, its accepted steps).
        finite: False where the step could not stay finite (or ended with |φ| past
            ``trig.DOMAIN``, 2⁵⁰ rad, where sines are NaN); there φ and φ' are the state
            before the step, unchanged, and every other float field is NaN.
        normal_force: N [N] (positive: pressing; see ``equations.contact_forces``).
        friction_force: F [N].
        energy: E [J].
        liftoff_margin: the smallest N/(m g) met during the step (<= 0: lift-off).
        slip_margin: the smallest (μN − |F|)/(m g) met during the step (< 0: slip).
        error_estimate: the sum of the accepted substeps' estimated errors (max of |Δφ|
            [rad], |Δφ'| [rad/s]), for rk8 and rk4 the larger of that and the same estimates
            carried to the step's end by the linearized motion, and for a step checked by
            reruns (``taylor_kernel.SHADOW_RATE``) at least its end's distance from theirs;
            for euler and midpoint, Richardson's estimate from the same step in half as many
            substeps (2 for one; NaN where the prediction already failed); NaN for DOP853.
        tol_met: False where the accepted substeps' error estimates add up to more than the
            scheme's share of ``tolerance`` (substeps accepted at float64 rounding or past the
            budget: the tolerance was out of reach and is not verified), or, for rk8 and rk4,
            where their carried estimate stays above the scheme's ``propagated_limit`` share
            of ``tolerance`` after ``RETRIES`` retries with smaller shares, or, for a step of
            rk8 or rk4 or a rounding-bound step of taylor, where its end lies farther than
            ``tolerance / SHADOW_MARGIN`` from the ends of taylor's reruns at smaller
            shares (float64's rounding grown along the step); for euler and
            midpoint, where the predicted substeps were more than ``MAX_SUBSTEPS`` or
            the error estimate is above ``tolerance``; for
            DOP853, where scipy failed or raised rtol = ``tol`` to its floor, 100 ε.
    """

    phi: np.ndarray | float
    phi_dot: np.ndarray | float
    phi_ddot: np.ndarray | float
    substeps: np.ndarray | int
    finite: np.ndarray | bool
    normal_force: np.ndarray | float
    friction_force: np.ndarray | float
    energy: np.ndarray | float
    liftoff_margin: np.ndarray | float
    slip_margin: np.ndarray | float
    error_estimate: np.ndarray | float
    tol_met: np.ndarray | bool

    @property
    def lifting(self) -> np.ndarray | bool:
        """True where the roller left the surface (N <= 0) during the step."""
        return self.liftoff_margin <= 0

    @property
    def slipping(self) -> np.ndarray | bool:
        """True where the friction needed exceeded μN during the step."""
        return self.slip_margin < 0


#: The fields of a step's outcome, in the order of :class:`StepResult`.
STEP_FIELDS = tuple(f.name for f in fields(StepResult))
#: The type of each field of one roller's result (the kernels store all as float64).
_KIND = {name: {"substeps": int, "finite": bool, "tol_met": bool}.get(name, float)
         for name in STEP_FIELDS}
#: The rows of a kernel's ``io`` table.
ROWS = SCENE_FIELDS + INPUT_FIELDS + CARRY_FIELDS + STEP_FIELDS
_ROW = {name: i for i, name in enumerate(ROWS)}
# Row numbers as compile-time constants of the kernels.
(_M, _RR, _KAPPA, _E, _K, _G, _C, _MU) = (_ROW[f] for f in SCENE_FIELDS)
(_PHI_IN, _W_IN, _TAU) = (_ROW[f] for f in INPUT_FIELDS)
_H_NEXT = _ROW["h_next"]
(_PHI, _W, _ACC, _NSUB, _FINITE, _NORMAL, _FRICTION, _ENERGY, _LIFT, _SLIP, _ERR,
 _TOL_MET) = (_ROW[f] for f in STEP_FIELDS)
_OUT = _PHI  # the outputs are the last rows, in STEP_FIELDS order
assert ROWS[_OUT:] == STEP_FIELDS
#: A stepper's settings, as the kernels read them from its float64 array ``cfg``: the control
#: step [s], ``tolerance``, the fixed substeps (0: automatic), and its scheme's controller halvings,
#: order, constant, stable step, sweep exponent, tol_share and propagated_limit (:class:`Scheme`).
CFG_FIELDS = ("dt", "tolerance", "substeps", "halvings", "order", "constant", "stable_step",
              "sweep_exponent", "tol_share", "propagated_limit")
(_CF_DT, _CF_TOLERANCE, _CF_SUBSTEPS, _CF_HALVINGS, _CF_ORDER, _CF_CONSTANT, _CF_STABLE, _CF_SWEEP,
 _CF_SHARE, _CF_PROPAGATED) = range(len(CFG_FIELDS))


def scene_arrays(scene: Scene, n: int | None = None) -> np.ndarray:
    """The kernels' per-roller scene numbers: shape ``(len(SCENE_FIELDS), n)``, float64.

    A scalar scene is broadcast to ``n`` rollers (1 if ``n`` is None); a batch scene gives its
    rollers (``n`` must then be None or its size).
    """
    values = (*scene.params, scene.mu)  # the order of SCENE_FIELDS
    size = scene.batch_size
    if n is None:
        n = size or 1
    elif size is not None and size != n:
        raise ValueError(f"n={n} does not match the scene's batch size {size}")
    out = np.empty((len(SCENE_FIELDS), n))
    if size is None:
        out[...] = np.array(values, dtype=float)[:, None]
    else:
        for i, value in enumerate(values):
            out[i] = np.asarray(value, dtype=float).reshape(-1)  # broadcast if a scalar
    return out


#: Unused elements at the end of each row of a chunk's scratch block and of a batch's tables
#: (:func:`row_table`), so that rows are not a power of two apart: the same element of many
#: rows would otherwise fall into one set of the cache, and a loop that reads many rows at
#: once (the stages read up to 30) would miss it at every element.
_PAD = 8


def check_memory(argument: str, count: int, bytes_each: int) -> None:
    """Refuse ``count`` (the value of ``argument``) items of up to ``bytes_each`` bytes whose
    arrays would not fit in the machine's physical memory (where the platform tells it), with
    a ValueError naming them, rather than fail in NumPy or be killed later."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, OSError, ValueError):  # not told: NumPy's MemoryError remains
        return
    need = count * bytes_each
    if need > total:
        gib = min(need, 2**1000) / 2**30  # (a float: a count past float's range overflows)
        raise ValueError(f"{argument}={shown(count)} is too many: their arrays need about "
                         f"{gib:.3g} GiB of memory (up to {bytes_each} bytes "
                         f"each), more than the machine's {total / 2**30:.3g} GiB; use fewer")


def row_table(rows: int, n: int, zeroed: bool = True) -> np.ndarray:
    """A float64 table of ``rows`` rows of ``n`` rollers whose rows lie ``n + _PAD`` elements
    apart in memory (a view): what the batch kernels read and write a roller's column of (see
    ``_PAD``). Zeroed, unless ``zeroed`` is False (for a table that is written whole)."""
    return (np.zeros if zeroed else np.empty)((rows, n + _PAD))[:, :n]


def as_row_table(table: np.ndarray) -> np.ndarray:
    """``table`` (float64, rows × rollers) in :func:`row_table`'s layout: itself where it has
    it, else a copy that has. Pickling copies a padded table into a compact one, which numba
    would compile every kernel for again."""
    if table.strides[0] == (table.shape[1] + _PAD) * table.itemsize:
        return table
    out = row_table(*table.shape, zeroed=False)
    out[...] = table
    return out

