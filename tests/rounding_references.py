"""References for steps whose error float64's rounding dominates, and how to make them again.

Two tight fits whose end state is up to 1.7e5 times as sensitive to a change of φ at the
start: :data:`TIGHT_RIM` (the mass near the rim, 16 steps of 0.05 s: the one a review found
reported within tol at 160 tol off, then 15 random), and the ``tight_fit`` preset (12 random
steps of 0.02 s, |φ'| up to 60 rad/s). DOP853 in float64 cannot resolve them (its runs at
1e-12 and 1e-13 differ by up to 8e-7), so the reference is the classical RK4 in 80-bit long
double with N fixed steps, written here from PHYSICS.md's closed form (not equations.py); its
uncertainty is |end(N) − end(N/2)| / 15 (fourth order). The scene numbers enter as the
kernels receive them: κ = 1/R and s = 1 − r κ rounded to float64 (s's rounding alone moves
the tight rim's ends by up to 3e-8; it belongs to the scene, not to a scheme).

``python tests/rounding_references.py`` writes ``tests/data/rounding_references.npz`` (about
ten minutes on one core).
"""

from __future__ import annotations

import pathlib
import time

import numpy as np
from roller_gym.physics import Scene, preset

DATA = pathlib.Path(__file__).parent / "data" / "rounding_references.npz"
TIGHT_RIM = Scene(R=0.1005, e=0.095, k=0.01, mu=5.0)
#: (name, scene, dt [s], fixed RK4 steps N)
GROUPS = (("tight_rim", TIGHT_RIM, 0.05, 3_200_000), ("tight_fit", preset("tight_fit"), 0.02,
                                                       800_000))


def starts(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(φ [rad], φ' [rad/s], τ [N·m]) of a group's steps."""
    if name == "tight_rim":
        rng = np.random.default_rng(41)
        phi = np.concatenate(([-14.024271288667641], rng.uniform(-20, 20, 15)))
        w = np.concatenate(([-7.478044108531909], rng.uniform(-10, 10, 15)))
        tau = np.concatenate(([0.49585930343837026], rng.uniform(-0.5, 0.5, 15)))
        return phi, w, tau
    scene = preset("tight_fit")
    rng = np.random.default_rng(3)
    phi, w = rng.uniform(-3, 3, 12), rng.uniform(-60, 60, 12)
    return phi, w, rng.uniform(-1, 1, 12) * scene.m * scene.g * scene.r


def rk4_long_double(scene: Scene, phi, w, tau, dt: float, n: int):
    """(φ, φ') after ``n`` classical RK4 steps of dt/n in np.longdouble, all starts at once."""
    ld = np.longdouble
    kappa64 = 1.0 / float(scene.R)
    s64 = 1.0 - float(scene.r) * kappa64  # as the kernels compute it
    m, r, e, k, g, c = (ld(float(x)) for x in (scene.m, scene.r, scene.e, scene.k, scene.g,
                                               scene.damping))
    kappa, s = ld(kappa64), ld(s64)
    tau = np.asarray(tau, dtype=ld)
    a1, a2, a3, rk = k * k + e * e + r * r, 2 * e * r, e * r / s, r * kappa / s

    def acc(p, v):  # φ'' of PHYSICS.md, θ = φ/s, ψ = r κ θ
        th = p / s
        lhs = (tau - c * v) / m - a3 * v * v * np.sin(th) - g * (r * np.sin(rk * p)
                                                                 + e * np.sin(p))
        return lhs / (a1 - a2 * np.cos(th))

    h = ld(dt) / n
    p, v = np.asarray(phi, dtype=ld), np.asarray(w, dtype=ld)
    for _ in range(n):
        k1p, k1v = v, acc(p, v)
        k2p, k2v = v + h / 2 * k1v, acc(p + h / 2 * k1p, v + h / 2 * k1v)
        k3p, k3v = v + h / 2 * k2v, acc(p + h / 2 * k2p, v + h / 2 * k2v)
        k4p, k4v = v + h * k3v, acc(p + h * k3p, v + h * k3v)
        p = p + h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p)
        v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return p, v


def load() -> dict[str, tuple[Scene, float, tuple, np.ndarray, np.ndarray]]:
    """{group: (scene, dt, starts, reference (2, n) [rad, rad/s], its uncertainty (n,))}."""
    data = np.load(DATA)
    return {name: (scene, dt, starts(name), data[f"{name}_end"], data[f"{name}_uncertainty"])
            for name, scene, dt, _ in GROUPS}


def main() -> None:
    out = {}
    for name, scene, dt, n in GROUPS:
        t0 = time.time()
        fine = np.stack(rk4_long_double(scene, *starts(name), dt, n))
        coarse = np.stack(rk4_long_double(scene, *starts(name), dt, n // 2))
        out[f"{name}_end"] = fine.astype(float)
        out[f"{name}_uncertainty"] = (np.abs(fine - coarse).max(axis=0) / 15).astype(float)
        print(f"{name}: {time.time() - t0:.0f} s, largest uncertainty "
              f"{out[f'{name}_uncertainty'].max():.2g}", flush=True)
    np.savez(DATA, **out)


if __name__ == "__main__":
    main()
