"""The physics of the driven roller: no Gymnasium here.

=====================  ================================================================
module                 what it holds
=====================  ================================================================
``scene``              :class:`Scene` (parameters, validation, shapes) and the presets
``equations``          each equation of ``docs/PHYSICS.md`` written once (floats, arrays, numba)
``trig``               sine and cosine without branches, so compiled loops over rollers vectorize
``forms``              the paper's forms of the theorem (Eqs. 15, 18, 24, 30), as references
``analysis``           kinematics, contact forces, energy, equilibria, linearization
``integrators``        one control step at constant torque (a package): the table of schemes
                       (taylor, the default, rk8 and rk4 error-controlled; semi-implicit Euler
                       and implicit midpoint at fixed substeps; scipy's DOP853), their compiled
                       kernels, the steppers (``docs/INTEGRATORS.md``)
``taylor``             the Taylor series of the motion, written out by a generator into
                       ``_taylor_series_<degree>`` (what the ``taylor`` scheme expands)
``compiling``          how the small compiled functions are inlined; a line on stderr where
                       compiling a kernel for its first use takes long
=====================  ================================================================
"""

from roller_gym.physics import analysis, compiling
from roller_gym.physics.analysis import *  # noqa: F403  (its __all__: kinematics, contact, energy, ...)
from roller_gym.physics.forms import FORMS
from roller_gym.physics.integrators import (
    INTEGRATORS,
    SCHEMES,
    BatchStepper,
    Stepper,
    StepResult,
    predicted_substeps,
    step,
)
from roller_gym.physics.scene import PRESETS, Scene, preset

compiling.install()

__all__ = [
    *analysis.__all__,
    "FORMS",
    "INTEGRATORS",
    "SCHEMES",
    "BatchStepper",
    "Stepper",
    "PRESETS",
    "Scene",
    "StepResult",
    "predicted_substeps",
    "preset",
    "step",
]
