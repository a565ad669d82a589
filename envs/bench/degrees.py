"""What the ``"taylor"`` scheme's degree costs at each tolerance: the measurement behind
:func:`roller_gym.physics.taylor.degree`.

One core (a :class:`BatchStepper` of :data:`ROLLERS`, below the parallel threshold), the
default scene ``paper`` and the stiff ``rim_mass``, random states carried along a trajectory
under random torques; each degree offered, at each tolerance, timed interleaved in one
process (:mod:`.timing`), best of the repeats. Run: ``python -m roller_gym.bench.degrees``
(it prints a table; nice it on a shared machine).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from roller_gym.bench import timing
from roller_gym.physics import BatchStepper, preset, taylor
from roller_gym.physics.integrators import SCHEMES

#: Rollers per batch: one core's (below ``PARALLEL_THRESHOLD``).
ROLLERS = 1024
#: Control steps per timed run, and the control step [s].
STEPS, DT = 200, 0.05
TOLS = (1e-2, 1e-3, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 1e-8)
SCENES = ("paper", "rim_mass")
#: The largest |φ'| [rad/s] of the random states.
W_MAX = 8.0


def random_states(scene: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(φ [rad], φ' [rad/s], τ [N·m] per step) on the preset ``scene``: |φ| <= π, |φ'| <=
    W_MAX, |τ| <= m g (r + e)/2; the torques (STEPS × n) drawn anew each step."""
    m, r, _, e, _, g, _ = preset(scene).params
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-math.pi, math.pi, n)
    w = rng.uniform(-W_MAX, W_MAX, n)
    tau = rng.uniform(-0.5, 0.5, (STEPS, n)) * m * g * (r + e)
    return phi, w, tau


def measure(scene: str = "paper", tols: tuple[float, ...] = TOLS,
            degrees: tuple[int, ...] = taylor.DEGREES, repeats: int = 7,
            seed: int = 0) -> list[dict[str, float]]:
    """On the preset ``scene``, per tolerance and degree: control steps per second [1/s]
    (rollers × steps over the best wall time) and accepted substeps per control step
    (mean)."""
    phi0, w0, tau = random_states(scene, ROLLERS, seed)
    runs, substeps = {}, {}
    for tol in tols:
        for degree in degrees:
            stepper = BatchStepper(ROLLERS, dt=DT, tolerance=tol, degree=degree)
            stepper.set_scenes(preset(scene))
            assert not stepper.parallel

            def run(stepper: BatchStepper = stepper) -> float:
                stepper.forget()
                phi, w, count = phi0.copy(), w0.copy(), 0.0
                for torque in tau:
                    out = stepper.run(phi, w, torque)
                    phi[:], w[:] = out[0], out[1]
                    count += out[3].sum()
                return count

            substeps[tol, degree] = run() / (ROLLERS * STEPS)  # (and compiled before timing)
            runs[tol, degree] = timing.clocked(run)
    best = timing.best(runs, repeats)
    return [{"tol": tol, "degree": degree, "chosen": float(taylor.degree(tol) == degree),
             "steps_per_s": ROLLERS * STEPS / best[tol, degree],
             "substeps": substeps[tol, degree]} for tol, degree in runs]


def main(argv: list[str] | None = None) -> None:
    """Print :func:`measure`'s table (M steps/s, substeps per step; * the rule's choice)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--tols", type=float, nargs="+", default=TOLS)
    parser.add_argument("--scenes", nargs="+", default=SCENES)
    args = parser.parse_args(argv)
    assert SCHEMES["taylor"].degrees == taylor.DEGREES
    for scene in args.scenes:
        rows = measure(scene, tuple(args.tols), repeats=args.repeats)
        print(f"{ROLLERS} rollers of {scene}, one core, {STEPS} steps of {DT} s, best of "
              f"{args.repeats}: M steps/s (substeps per step); * the rule's degree")
        for tol in args.tols:
            cells = [f"{r['degree']:.0f}{'*' if r['chosen'] else ' '} "
                     f"{r['steps_per_s'] / 1e6:6.3f} ({r['substeps']:.2f})"
                     for r in rows if r["tol"] == tol]
            print(f"tol {tol:.0e}: " + "   ".join(cells))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
