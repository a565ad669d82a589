"""Integration over one control step of constant torque: the schemes, their compiled
kernels and the steppers that run them. Why each rule is what it is, what was measured and
what was tried: ``docs/INTEGRATORS.md``.

**Schemes** (:data:`SCHEMES`, one :class:`Scheme` row each; the ``integrator`` argument is its
key): ``"taylor"`` (the default: the Taylor series of the motion to degree 18, its substep
size chosen after expanding), ``"rk8"`` (Dormand–Prince 8(5,3)) and ``"rk4"``
(Bogacki–Shampine 5(4); classical RK4 with fixed ``substeps``) under error control;
``"euler"`` (semi-implicit) and ``"midpoint"`` (implicit, symplectic) at fixed substeps;
``"dop853"`` (scipy's, the slow reference).

**Contract.** Under error control, the accepted substeps' error estimates (max of |Δφ| [rad]
and |Δφ'| [rad/s]) add up to at most the scheme's ``tol_share · tol`` over a control step,
or the step reports ``tol_met=False`` (the tolerance was out of float64's reach, or of
``MAX_SUBSTEPS``), and the steppers warn once; nothing loops on an unreachable tolerance.
A step that cannot stay finite reports ``finite=False``, the state before the step and NaN
in every other float field. The margins are the smallest met at the start of every
accepted substep and at the end. A roller's result is bit for bit the same alone and in
any batch.

=================  ==========================================================================
module             what it holds
=================  ==========================================================================
``layout``         the rows of the kernels' ``io`` table, :class:`StepResult`, ``cfg``
``rules``          what the kernels share: budget, rounding rule, prediction, lane loops, output
``rk``             the Runge–Kutta pairs' coefficients and kernels
``taylor_kernel``  the ``taylor`` scheme's substep and kernels
``fixed``          the fixed-substep schemes (euler, midpoint)
``reference``      scipy's DOP853 as a scheme
``schemes``        the table :data:`SCHEMES`, :func:`scheme`, each scheme's kernels
``steppers``       :class:`Stepper`, :class:`BatchStepper`, :func:`step`, :func:`contact_state`
=================  ==========================================================================
"""

from roller_gym.physics.integrators.layout import (
    CARRY_FIELDS,
    CFG_FIELDS,
    INPUT_FIELDS,
    ROWS,
    SCENE_FIELDS,
    STEP_FIELDS,
    StepResult,
    as_row_table,
    row_table,
    scene_arrays,
)
from roller_gym.physics.integrators.rules import (
    CHUNK,
    MAX_SUBSTEPS,
    PARALLEL_THRESHOLD,
    ROUNDOFF_FACTOR,
    at_rest,
)
from roller_gym.physics.integrators.schemes import (
    DEFAULT_INTEGRATOR,
    INTEGRATORS,
    SCHEMES,
    Scheme,
    scheme,
)
from roller_gym.physics.integrators.steppers import (
    CONTACT_FIELDS,
    BatchStepper,
    Stepper,
    contact_state,
    missed,
    predicted_substeps,
    put_inputs,
    step,
)
from roller_gym.physics.integrators.taylor_kernel import ROUNDING_SHARE, TAYLOR_ROUNDING

# The kernels' internals that the tests and the benchmark reach into, where they were before
# the module became a package.
from roller_gym.physics.integrators.layout import _PAD, _ROW  # noqa: F401  isort: skip
from roller_gym.physics.integrators.rk import _rk_chunk, _rk_one  # noqa: F401  isort: skip
from roller_gym.physics.integrators.rules import (  # noqa: F401  isort: skip
    _accel_lanes,
    _end_lanes,
    _margin_lanes,
)
from roller_gym.physics.integrators.taylor_kernel import (  # noqa: F401  isort: skip
    _T_IN,
    _T_WIDTH,
    _TI_FLOOR,
    _TI_PHI,
    _TI_REST,
    _TI_TAU,
    _TI_W,
    _taylor_chunk,
    _taylor_lanes,
    _taylor_one,
)

__all__ = [
    "CARRY_FIELDS",
    "CFG_FIELDS",
    "CHUNK",
    "CONTACT_FIELDS",
    "DEFAULT_INTEGRATOR",
    "INPUT_FIELDS",
    "INTEGRATORS",
    "MAX_SUBSTEPS",
    "PARALLEL_THRESHOLD",
    "ROUNDING_SHARE",
    "ROUNDOFF_FACTOR",
    "ROWS",
    "SCENE_FIELDS",
    "SCHEMES",
    "STEP_FIELDS",
    "TAYLOR_ROUNDING",
    "BatchStepper",
    "Scheme",
    "StepResult",
    "Stepper",
    "as_row_table",
    "at_rest",
    "contact_state",
    "missed",
    "predicted_substeps",
    "put_inputs",
    "row_table",
    "scene_arrays",
    "scheme",
    "step",
]
