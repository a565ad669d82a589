"""The table of schemes, :data:`SCHEMES` (one :class:`Scheme` row each; the ``integrator``
argument is its key), the default :data:`DEFAULT_INTEGRATOR`, each scheme's compiled kernels,
and the check of a step's arguments (dt, tolerance, substeps).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from roller_gym.physics import taylor
from roller_gym.physics.integrators.fixed import (
    _euler_kernel,
    _euler_substep,
    _midpoint_kernel,
    _midpoint_substep,
)
from roller_gym.physics.integrators.reference import _dop853_kernel
from roller_gym.physics.integrators.rk import (
    _BS5,
    _DOP853,
    _RK4,
    _rk_chunk,
    _rk_one,
    _rk_parallel,
    _rk_serial,
)
from roller_gym.physics.integrators.rules import MAX_SUBSTEPS
from roller_gym.physics.integrators.taylor_kernel import (
    _taylor_chunk,
    _taylor_one,
    _taylor_parallel,
    _taylor_serial,
    _taylor_substep,
    taylor_kernels,
)
from roller_gym.physics.scene import finite_real, shown, whole_number


@dataclass(frozen=True)
class Scheme:
    """One integration scheme: a row of :data:`SCHEMES`.

    Attributes:
        name: its name, the ``integrator`` argument.
        order: its order of accuracy.
        stable_step: the largest λh per substep (λ the fastest rate), inside its stability
            region with room to spare (``math.inf``: A-stable).
        adaptive: True if its substeps follow an error estimate (``docs/INTEGRATORS.md``).
        substep: its substep function (for the Runge–Kutta pairs, the shared pair kernel).
        kernel: for a fixed-substep scheme, its compiled kernel: ``_fixed_steps`` around
            ``substep``, written as a function of its own (two lines) so that numba caches it;
            for ``"taylor"``, its serial kernel.
        parallel: the kernel for large batches, where it is not ``kernel``.
        chunk: for a scheme whose batch kernels advance chunks of rollers in lanes, that
            function, ``chunk(io, lo, hi, tableau, cfg)`` (rollers lo..hi−1): what a caller
            fusing more work into the same pass over chunks calls (:meth:`BatchStepper.run`).
        one: for a scheme with a kernel of its own for one roller (``_rk_one``,
            ``_taylor_one``: the chunk's arithmetic without lanes), that kernel,
            ``one(io, tableau, cfg)`` on column 0: what a caller fusing more work into one
            roller's step calls (:meth:`Stepper.bind`), so that it compiles no lanes.
        tableau: for an explicit Runge–Kutta pair, its coefficients (see ``_tableau``).
        fixed_tableau: the coefficients its fixed substeps (``substeps=n``) take, where they
            differ from ``tableau`` (rk4: classical RK4; under error control,
            Bogacki–Shampine 5(4)).
        constant: C of the substep prediction n = (C (λ dt)^(p+1) / tolerance)^(1/p), calibrated
            on the presets (for the adaptive schemes only the first step-size guess).
        sweep_exponent: the exponent of re/(k² + (r − e)²) in the prediction's sweep rate.
        halvings: the adaptive controller takes the 2^halvings-th root of the error ratio
            (2 or 3: the kernel takes it as square roots, which vectorize).
        tol_share: the share of ``tolerance`` the accepted substeps' error estimates may add up to
            (below 1: room for what the estimates miss, measured in the tests; each row's
            value and what it was measured against: ``docs/INTEGRATORS.md``).
        propagated_limit: a Runge–Kutta pair's step reports ``tol_met`` only if its accepted
            substeps' estimates, carried to the step's end by the linearized motion, stay
            within this share of ``tolerance`` (above it the step is taken again with a smaller
            share, at most ``RETRIES`` times; ``docs/INTEGRATORS.md``).
        degrees: for a scheme offered at several degrees (``"taylor"``: ``taylor.DEGREES``),
            those; ``order`` is then the default tolerance's, and the kernels above are its.
        degree_rule: for such a scheme, the rule choosing the degree from ``tolerance``
            (``taylor.degree``).
    """

    name: str
    order: int
    stable_step: float
    adaptive: bool
    substep: Callable | None
    tableau: np.ndarray | None = None
    fixed_tableau: np.ndarray | None = None
    kernel: Callable | None = None
    parallel: Callable | None = None
    chunk: Callable | None = None
    one: Callable | None = None
    constant: float = 0.0
    sweep_exponent: float = 0.5
    halvings: int = 0
    tol_share: float = 1.0
    propagated_limit: float = math.inf
    degrees: tuple[int, ...] = ()
    degree_rule: Callable[[float], int] | None = None

    def degree(self, tolerance: float) -> int:
        """The order a step at ``tolerance`` runs at: the degree the rule chooses, or
        ``order`` for a scheme of one."""
        return self.order if self.degree_rule is None else self.degree_rule(tolerance)

    def kernels(self, degree: int | None = None) -> tuple[Callable, Callable]:
        """(serial, parallel) kernels ``f(io, tableau, cfg)`` of this scheme (at ``degree``,
        one of ``degrees``, for a scheme offering several; None: ``order``)."""
        if degree is None or degree == self.order:
            return _kernels(self)
        if degree not in self.degrees:
            raise ValueError(f"degree={shown(degree)}: integrator={shown(self.name)} offers "
                             f"{self.degrees or (self.order,)}")
        k = taylor_kernels(degree)
        return k.serial, k.parallel

    def __reduce__(self) -> tuple[Callable, tuple[str]]:
        """Pickled by name: unpickled, it is the row of :data:`SCHEMES` (its compiled
        functions those of this process)."""
        return scheme, (self.name,)

    def pair(self, fixed: bool) -> np.ndarray | None:
        """The coefficients its kernel takes: under error control, or with ``fixed`` substeps."""
        return self.fixed_tableau if fixed and self.fixed_tableau is not None else self.tableau

    def evaluations(self, fixed: bool) -> int:
        """Right-hand-side evaluations per substep of a Runge–Kutta pair (the first stage is
        the last substep's end, evaluated once): under error control, or with ``fixed``
        substeps. A substep of ``"taylor"`` is one expansion, counted as one."""
        pair = self.pair(fixed)
        return 1 if pair is None else pair.shape[0] - 3


_SCHEME_LIST = (
    Scheme("rk8", 8, 1.0, True, _rk_chunk, _DOP853, chunk=_rk_chunk, one=_rk_one,
           constant=1e-6, sweep_exponent=0.75, halvings=3, tol_share=0.1,
           propagated_limit=0.5),
    Scheme("rk4", 4, 1.0, True, _rk_chunk, _BS5, fixed_tableau=_RK4, chunk=_rk_chunk,
           one=_rk_one, constant=0.02, halvings=2, tol_share=0.12, propagated_limit=2.0),
    Scheme("euler", 1, 0.5, False, _euler_substep, kernel=_euler_kernel, constant=2.0),
    Scheme("midpoint", 2, math.inf, False, _midpoint_substep, kernel=_midpoint_kernel,
           constant=0.3),
    Scheme("taylor", taylor.ORDER, 1.0, True, _taylor_substep, kernel=_taylor_serial,
           parallel=_taylor_parallel, chunk=_taylor_chunk, one=_taylor_one,
           constant=1e-6, tol_share=0.01, degrees=taylor.DEGREES, degree_rule=taylor.degree),
    Scheme("dop853", 8, math.inf, True, None),
)
#: The schemes by name.
SCHEMES: dict[str, Scheme] = {s.name: s for s in _SCHEME_LIST}
#: The schemes by name (the ``integrator`` arguments are its keys).
INTEGRATORS = SCHEMES
DEFAULT_INTEGRATOR = "taylor"

_KERNELS: dict[str, tuple[Callable, Callable]] = {}


def _kernels(scheme: Scheme) -> tuple[Callable, Callable]:
    """The factory: one compiled kernel per scheme (serial, parallel), made once."""
    if scheme.name not in _KERNELS:
        if scheme.substep is None:
            pair = (_dop853_kernel, _dop853_kernel)
        elif scheme.tableau is not None:
            pair = (_rk_serial, _rk_parallel)
        else:
            pair = (scheme.kernel, scheme.parallel or scheme.kernel)
        _KERNELS[scheme.name] = pair
    return _KERNELS[scheme.name]


def scheme(integrator: str) -> Scheme:
    """The row of :data:`SCHEMES` called ``integrator``."""
    try:
        return SCHEMES[integrator]
    except (KeyError, TypeError):
        raise ValueError(f"unknown integrator {shown(integrator)}; allowed: "
                         f"{', '.join(INTEGRATORS)}") from None


def _check_step_args(dt: float, tolerance: float, substeps: int | None) -> None:
    if not (finite_real(dt) and float(dt) > 0):
        raise ValueError(f"dt={shown(dt)} [s] must be a number, finite and > 0")
    if not (finite_real(tolerance) and float(tolerance) > 0):
        raise ValueError(f"tolerance={shown(tolerance)} must be a number, finite and > 0")
    if substeps is not None and not (
        whole_number(substeps) and 1 <= substeps <= MAX_SUBSTEPS
    ):
        raise ValueError(
            f"substeps={shown(substeps)} must be None (automatic) or an integer in [1, "
            f"{MAX_SUBSTEPS}]"
        )

