"""Temporary: the stepper interface over the fixed-substep kernels (replaced by the
integrators' own steppers)."""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from roller_gym.physics import Scene
from roller_gym.physics import integrators as integ

STEP_FIELDS = ("phi", "phi_dot", "phi_ddot", "substeps", "finite", "normal_force",
               "friction_force", "energy", "liftoff_margin", "slip_margin")
StepFloats = namedtuple("StepFloats", STEP_FIELDS)
_NAN_FIELDS = (2, 5, 6, 7, 8, 9)


def _row(scene: Scene) -> tuple[float, ...]:
    return (*(float(p) for p in scene.params), float(scene.mu))


class Stepper:
    def __init__(self, scene: Scene, *, method: str = "rk8", dt: float, tol: float,
                 substeps: int | None = None) -> None:
        self.method, self.dt, self.tol = method, dt, tol
        self._buf = np.zeros(integ.BUFFER_SIZE)
        if method != "dop853":
            self._buf[11:15] = (dt, tol, integ.METHODS[method], substeps or 0)
        self.substeps = substeps
        self.set_scene(scene)

    def set_scene(self, scene: Scene) -> None:
        self.scene = scene
        self._buf[3:11] = _row(scene)

    def advance(self, phi: float, phi_dot: float, tau: float) -> StepFloats:
        if self.method == "dop853":
            r = integ.step(self.scene, phi, phi_dot, tau, self.dt, method="dop853", tol=self.tol)
            out = [getattr(r, f) for f in STEP_FIELDS]
        else:
            buf = self._buf
            buf[0], buf[1], buf[2] = phi, phi_dot, tau
            integ.advance_into(buf)
            out = buf[integ.OUT:integ.OUT + 10].tolist()
        out[3], out[4] = int(out[3]), bool(out[4])
        if not out[4]:
            for j in _NAN_FIELDS:
                out[j] = float("nan")
        return StepFloats(*out)


class BatchStepper:
    def __init__(self, num: int, *, method: str = "rk8", dt: float, tol: float,
                 substeps: int | None = None) -> None:
        self.num, self.dt, self.tol = num, dt, tol
        self.code, self.substeps = integ.METHODS[method], substeps or 0
        self._rows = np.zeros((num, 8))
        self._raw = np.empty((10, num))

    def set_scenes(self, scene: Scene, index=None) -> None:
        idx = slice(None) if index is None else index
        cols = [np.asarray(p, float) for p in (*scene.params, scene.mu)]
        n = len(np.arange(self.num)[idx])
        self._rows[idx] = np.stack([np.broadcast_to(c, (n,)) for c in cols], axis=1)

    def advance(self, phi: np.ndarray, phi_dot: np.ndarray, tau: np.ndarray) -> StepFloats:
        raw = self._raw
        integ.advance_batch(self._rows, np.ascontiguousarray(phi, float),
                            np.ascontiguousarray(phi_dot, float),
                            np.ascontiguousarray(tau, float), self.dt, self.code, self.tol,
                            self.substeps, raw)
        finite = raw[4] != 0
        fields = [raw[j].copy() for j in range(10)]
        fields[3], fields[4] = raw[3].astype(np.int64), finite
        for j in _NAN_FIELDS:
            fields[j][~finite] = np.nan
        return StepFloats(*fields)
