"""The cost of the error control: the automatic substep count of taylor, rk8 and rk4 against the
smallest fixed count of equal substeps that meets the same tolerance, on the same steps.

:func:`measure` returns plain data (saved by :mod:`roller_gym.bench.report` under the
results' ``"cost"`` key, judged by :func:`roller_gym.bench.verdicts.verdict_cost`).

**The sample.** Independent control steps of ``DT`` seconds drawn by :func:`adversarial_sample`
(seeded): scenes inside a cylinder, nearly tight (R/r − 1 down to 0.005), on a floor and on a
drum; e/r up to 0.999, k/r down to 0.01; |τ| up to 5 m g r; |φ'| up to 15 sqrt(g/r).

**Per step and tolerance:**

* the reference: DOP853 (``integrators.step(method="dop853")``) at rtol = atol =
  ``REFERENCE_TOL``, run again at ten times that to estimate its own error; a step whose two
  runs differ by more than ``tol · UNCERTAINTY_SHARE`` is skipped (its errors near ``tol``
  cannot be told);
* the automatic count: ``integrators.step`` (stateless: the first substep predicted), the
  accepted substeps it reports, and its error against the reference;
* the smallest fixed count: the least n whose n equal substeps of the same scheme
  (``substeps=n``) end within ``tol`` of the reference, found by :func:`smallest_fixed_counts`
  (doubling, then bisection between n/2 and n); a step no count up to ``MAX_FIXED`` meets is
  skipped (the tolerance is out of reach of float64 there).

The ratio automatic / smallest is reported per tolerance and scheme, counted in
right-hand-side evaluations (the same as substeps for rk8, and for taylor, whose substeps are
one expansion each; rk4's substep under error control is a Bogacki–Shampine 5(4) step of 7
evaluations, its fixed substep one classical step of 4): its median, 99th percentile and
largest, with the share of steps whose automatic error is within ``tol``.

**Two variants.** ``stateless``: the sample's independent steps, each started afresh as
``integrators.step`` does; the verdict uses it, since the sample is of independent control
steps. ``carried``: along short reference trajectories from the sample's first states
(random torques of the same range each step, :func:`reference_trajectories`), each step
taken from its reference state by one :class:`~roller_gym.physics.integrators.BatchStepper`
that carries each roller's proposed substep size from one step to the next, as the
environments step (:func:`carried_steps`); the first step of each trajectory (predicted, as
stateless) is left out. What an environment gets after its first step.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym.bench import records, timing
from roller_gym.config import DEFAULT_DT
from roller_gym.episode import take
from roller_gym.physics import Scene
from roller_gym.physics import integrators as integ

__all__ = ["DT", "MAX_FIXED", "REFERENCE_TOL", "UNCERTAINTY_SHARE", "CostConfig",
           "Trajectories", "adversarial_sample", "carried_steps", "compare", "fixed_errors",
           "measure", "reference_trajectories", "references", "smallest_fixed_counts"]

#: The control step [s] (the environments' default).
DT = float(DEFAULT_DT)
#: The reference: DOP853 at rtol = atol = REFERENCE_TOL (and again at 10 × it).
REFERENCE_TOL = 1e-13
#: A step is skipped where the two reference runs differ by more than this share of tol.
UNCERTAINTY_SHARE = 0.1
#: The largest fixed count tried (the most substeps a step may take).
MAX_FIXED = integ.MAX_SUBSTEPS
#: Rollers per reference run (DOP853 integrates them as one system, with one error norm:
#: similar stiffness together, few enough that none is under-resolved).
REFERENCE_GROUP = 25
#: Gravity [m/s²] (the scenes' default).
G = float(Scene.g)


@dataclass(frozen=True)
class CostConfig:
    """What :func:`measure` measures; :meth:`make` with ``quick`` a smaller sample."""

    steps: int = 300  # independent control steps of the stateless variant
    trajectories: int = 40  # trajectories of the carried variant ...
    trajectory_steps: int = 6  # ... of this many control steps (the first one left out)
    methods: tuple[str, ...] = ("taylor", "rk8", "rk4")
    tols: tuple[float, ...] = (1e-6, 1e-8)
    seed: int = 1

    @classmethod
    def make(cls, quick: bool) -> CostConfig:
        """The full sample, or with ``quick`` a small one."""
        return cls(steps=60, trajectories=10, trajectory_steps=4) if quick else cls()


def adversarial_sample(n: int, seed: int) -> tuple[Scene, np.ndarray, np.ndarray, np.ndarray]:
    """``n`` random hard control steps: (a batch scene, φ [rad], φ' [rad/s], τ [N·m]).

    Scenes in four families drawn alike: inside a cylinder (R/r from 1.5 to 10), nearly tight
    (R/r − 1 log-uniform from 0.005 to 0.1), on a floor, on a drum (−R/r from 1 to 10);
    r from 0.05 to 0.2 m, e/r uniform up to 0.999, k/r log-uniform from 0.01 to 1, m from
    0.5 to 2 kg, viscous damping in 30 % of them; |φ| <= π, |φ'| up to 15 sqrt(g/r),
    |τ| up to 5 m g r.
    """
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.05, 0.2, n)
    family = rng.integers(0, 4, n)
    R = np.select([family == 0, family == 1, family == 2],
                  [r * rng.uniform(1.5, 10, n), r * (1 + 10 ** rng.uniform(-2.3, -1, n)),
                   np.full(n, np.inf)], -r * rng.uniform(1, 10, n))
    e = r * rng.uniform(0, 0.999, n)
    k = r * 10 ** rng.uniform(-2, 0, n)
    m = rng.uniform(0.5, 2, n)
    c = np.where(rng.random(n) < 0.3, rng.uniform(0, 0.1, n) * m * r * r * np.sqrt(G / r), 0)
    phi = rng.uniform(-math.pi, math.pi, n)
    w = rng.uniform(-15, 15, n) * np.sqrt(G / r) * rng.random(n)
    tau = rng.uniform(-5, 5, n) * m * G * r
    return Scene(m=m, r=r, R=R, e=e, k=k, g=G, damping=c), phi, w, tau


def _take(scene: Scene, index: np.ndarray) -> Scene:
    """The rollers ``index`` of the batch ``scene`` (:func:`roller_gym.episode.take`)."""
    return take(scene, index, scene.batch_size or 1)


def references(scene: Scene, phi: np.ndarray, w: np.ndarray, tau: np.ndarray, dt: float = DT
               ) -> tuple[np.ndarray, np.ndarray]:
    """DOP853 over ``dt`` [s] from each state: (the end states, shape (2, n), at
    ``REFERENCE_TOL``; their uncertainty, shape (n,): the largest difference [rad, rad/s] from
    a run at 10 × ``REFERENCE_TOL``; inf where either run failed).

    The steps go in groups of ``REFERENCE_GROUP`` of similar predicted cost, each group one
    DOP853 system.
    """
    n = phi.size
    order = np.argsort(integ.predicted_substeps(scene, w, dt, 1e-8, "rk8"), kind="stable")
    runs = []
    for rtol in (REFERENCE_TOL, 10 * REFERENCE_TOL):
        out = np.empty((2, n))
        for group in np.array_split(order, max(1, math.ceil(n / REFERENCE_GROUP))):
            with np.errstate(all="ignore"):
                res = integ.step(_take(scene, group), phi[group], w[group], tau[group], dt,
                                 integrator="dop853", tolerance=rtol)
            out[0, group] = np.where(res.finite, res.phi, np.nan)
            out[1, group] = np.where(res.finite, res.phi_dot, np.nan)
        runs.append(out)
    diff = np.abs(runs[0] - runs[1]).max(axis=0)
    return runs[0], np.where(np.isfinite(diff), diff, np.inf)


def _errors(res: integ.StepResult, ref: np.ndarray) -> np.ndarray:
    """max(|Δφ| [rad], |Δφ'| [rad/s]) of each step against ``ref``; inf where not finite."""
    err = np.maximum(np.abs(res.phi - ref[0]), np.abs(res.phi_dot - ref[1]))
    return np.where(np.asarray(res.finite) & np.isfinite(err), err, np.inf)


def fixed_errors(scene: Scene, phi: np.ndarray, w: np.ndarray, tau: np.ndarray,
                 ref: np.ndarray, counts: np.ndarray, method: str, dt: float = DT
                 ) -> np.ndarray:
    """The error of each step taken in ``counts[i]`` equal substeps of ``method``, against
    ``ref`` (shape (2, n)); one batch per distinct count."""
    err = np.empty(phi.size)
    for n in np.unique(counts):
        idx = np.flatnonzero(counts == n)
        with np.errstate(all="ignore"):
            res = integ.step(_take(scene, idx), phi[idx], w[idx], tau[idx], dt, integrator=method,
                             substeps=int(n))
        err[idx] = _errors(res, ref[:, idx])
    return err


def smallest_fixed_counts(meets: Callable[[np.ndarray, np.ndarray], np.ndarray], size: int,
                          most: int = MAX_FIXED) -> np.ndarray:
    """The least count n in [1, ``most``] with ``meets`` true, per step (0 where none is).

    ``meets(index, counts)`` says, for the steps ``index`` (an index array), whether their
    counts ``counts`` meet the tolerance. Doubling (1, 2, 4, ..., then ``most``) finds the
    first that meets it; bisection between the one before (which does not) and n then finds the
    count n* that meets it where n* − 1 does not. The least count is that n* where meeting
    the tolerance is monotone in n, as the error of a convergent scheme is once its
    substeps resolve the motion.
    """
    hi = np.zeros(size, dtype=np.int64)
    lo = np.zeros(size, dtype=np.int64)
    todo = np.arange(size)
    n, below = 1, 0
    while todo.size:
        ok = meets(todo, np.full(todo.size, n))
        hi[todo[ok]], lo[todo[ok]] = n, below
        todo = todo[~ok]
        if n >= most:
            break
        n, below = min(2 * n, most), n
    while True:
        todo = np.flatnonzero((hi > 0) & (hi - lo > 1))
        if not todo.size:
            return hi
        mid = (lo[todo] + hi[todo]) // 2
        ok = meets(todo, mid)
        hi[todo[ok]] = mid[ok]
        lo[todo[~ok]] = mid[~ok]


def _stats(x: np.ndarray) -> dict[str, float]:
    if not x.size:
        return {"median": math.nan, "p99": math.nan, "max": math.nan, "mean": math.nan}
    return {"median": float(np.median(x)), "p99": float(np.percentile(x, 99)),
            "max": float(x.max()), "mean": float(x.mean())}


def compare(scene: Scene, phi: np.ndarray, w: np.ndarray, tau: np.ndarray,
            auto: integ.StepResult, ref: np.ndarray, uncertainty: np.ndarray, method: str,
            tol: float, dt: float = DT) -> dict[str, Any]:
    """One row of the results: the automatic counts (``auto``, the steps' results) against
    the smallest fixed counts that meet ``tol`` on the same steps."""
    n = phi.size
    err_auto = _errors(auto, ref)
    ok_ref = uncertainty <= UNCERTAINTY_SHARE * tol
    ok_auto = np.asarray(auto.finite, dtype=bool)
    keep = np.flatnonzero(ok_ref & ok_auto)

    def meets(index: np.ndarray, counts: np.ndarray) -> np.ndarray:
        i = keep[index]
        return fixed_errors(_take(scene, i), phi[i], w[i], tau[i], ref[:, i], counts, method,
                            dt) <= tol

    smallest = smallest_fixed_counts(meets, keep.size)
    found = smallest > 0
    used = keep[found]
    subs = np.asarray(auto.substeps, dtype=float)[used]
    # in right-hand-side evaluations: rk4's substep under error control is a step of its
    # 5(4) pair, its fixed substep a classical one; rk8's are the same
    scheme = integ.scheme(method)
    ratio = (subs * scheme.evaluations(fixed=False)
             / (smallest[found] * scheme.evaluations(fixed=True)))
    within = err_auto[used] <= tol
    met = np.asarray(auto.tol_met, dtype=bool)[used]
    return {
        "method": method, "tol": tol, "steps": n, "measured": int(used.size),
        "skipped": {"reference uncertain": int((~ok_ref).sum()),
                    "automatic step not finite": int((ok_ref & ~ok_auto).sum()),
                    f"no fixed count up to {MAX_FIXED:,} meets tol": int((~found).sum())},
        "ratio": _stats(ratio),
        "auto_substeps": _stats(subs),
        "fixed_substeps": _stats(smallest[found].astype(float)),
        "within_tol": float(within.mean()) if used.size else math.nan,
        "within_tol_where_met": float(within[met].mean()) if met.any() else math.nan,
        "worst_error_over_tol": float(err_auto[used].max() / tol) if used.size else math.nan,
        "tol_not_met": int((~met).sum()),
    }


@dataclass
class Trajectories:
    """Reference trajectories: ``states`` (steps + 1, 2, n) [rad, rad/s], each step's torques
    ``tau`` (steps, n) [N·m] and the reference's ``uncertainty`` per step (steps, n), for the
    ``scene`` (a batch of n) of the trajectories whose reference stayed finite."""

    scene: Scene
    states: np.ndarray
    tau: np.ndarray
    uncertainty: np.ndarray
    dropped: int  # trajectories left out: their reference went non-finite


def reference_trajectories(scene: Scene, phi: np.ndarray, w: np.ndarray, steps: int,
                           seed: int, dt: float = DT) -> Trajectories:
    """DOP853 (:func:`references`) along ``steps`` control steps from each state, under
    random torques of the sample's range (|τ| up to 5 m g r, drawn per step and roller)."""
    n = phi.size
    rng = np.random.default_rng(seed)
    m, r = (np.broadcast_to(np.asarray(x, dtype=float), (n,)) for x in (scene.m, scene.r))
    tau = rng.uniform(-5, 5, (steps, n)) * m * G * r
    states = np.full((steps + 1, 2, n), np.nan)
    unc = np.full((steps, n), np.inf)
    states[0] = phi, w
    for i in range(steps):
        live = np.flatnonzero(np.isfinite(states[i]).all(axis=0))
        ref, unc[i, live] = references(_take(scene, live), states[i, 0, live],
                                       states[i, 1, live], tau[i, live], dt)
        states[i + 1][:, live] = ref
    keep = np.flatnonzero(np.isfinite(states).all(axis=(0, 1)))
    return Trajectories(_take(scene, keep), states[:, :, keep], tau[:, keep], unc[:, keep],
                        n - keep.size)


def carried_steps(traj: Trajectories, method: str, tol: float, dt: float = DT
                  ) -> integ.StepResult:
    """Each step of ``traj`` taken from its reference state through one
    :class:`~roller_gym.physics.integrators.BatchStepper`, which carries each roller's
    proposed substep size from its step to the next, as the environments step: the results
    of the steps after the first (flattened, step-major), whose first substeps were carried."""
    steps, _, n = traj.states.shape
    stepper = integ.BatchStepper(n, integrator=method, dt=dt, tolerance=tol)
    stepper.set_scenes(traj.scene)
    out = []
    for i in range(steps - 1):
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # counted: tol_not_met
            res = stepper.advance(traj.states[i, 0], traj.states[i, 1], traj.tau[i])
        if i > 0:
            out.append({f: np.array(getattr(res, f)) for f in integ.STEP_FIELDS})
    return integ.StepResult(*(np.concatenate([o[f] for o in out]) for f in integ.STEP_FIELDS))


def measure(cfg: CostConfig, command: str = "",
            progress: Callable[[str], None] = timing.progress) -> dict[str, Any]:
    """The cost measurement: for every method and tolerance of ``cfg``, a row per variant
    (``"stateless"`` and ``"carried"``, see the module docs); plain data, with the
    ``command`` that ran it and the date."""
    t0 = time.perf_counter()
    date = records.now()
    progress(f"cost: the references of {cfg.steps} hard steps and of their trajectories")
    scene, phi, w, tau = adversarial_sample(cfg.steps, cfg.seed)
    ref, unc = references(scene, phi, w, tau)
    starts = np.arange(min(cfg.trajectories, cfg.steps))
    traj = reference_trajectories(_take(scene, starts), phi[starts], w[starts],
                                  cfg.trajectory_steps, cfg.seed + 1)
    # the carried steps, flattened as carried_steps gives them: steps 1 .. steps − 1
    k = traj.states.shape[2]
    t_scene = _take(traj.scene, np.tile(np.arange(k), cfg.trajectory_steps - 1))
    t_phi, t_w = (traj.states[1:-1, j].reshape(-1) for j in (0, 1))
    t_tau = traj.tau[1:].reshape(-1)
    t_ref = traj.states[2:].transpose(1, 0, 2).reshape(2, -1)
    t_unc = traj.uncertainty[1:].reshape(-1)
    progress(f"cost: references of {cfg.steps} steps and {k} trajectories of "
             f"{cfg.trajectory_steps} steps ({time.perf_counter() - t0:.0f} s)")
    rows = []
    for method in cfg.methods:
        for tol in cfg.tols:
            progress(f"cost {method} tol {tol:.0e}: automatic against smallest fixed counts")
            t1 = time.perf_counter()
            with np.errstate(all="ignore"):
                auto = integ.step(scene, phi, w, tau, DT, integrator=method, tolerance=tol)
            row = compare(scene, phi, w, tau, auto, ref, unc, method, tol)
            rows.append({"variant": "stateless", **row})
            carried = carried_steps(traj, method, tol)
            row_c = compare(t_scene, t_phi, t_w, t_tau, carried, t_ref, t_unc, method, tol)
            rows.append({"variant": "carried", **row_c})
            progress(f"cost {method} tol {tol:.0e}: automatic / smallest fixed count, median "
                     f"{row['ratio']['median']:.2f}, 99th percentile {row['ratio']['p99']:.2f} "
                     f"(carried: {row_c['ratio']['median']:.2f}, {row_c['ratio']['p99']:.2f}); "
                     f"{time.perf_counter() - t1:.0f} s")
    return {
        "settings": {"dt": DT, "steps": cfg.steps, "trajectories": cfg.trajectories,
                     "trajectory_steps": cfg.trajectory_steps, "seed": cfg.seed,
                     "trajectories_dropped": traj.dropped,
                     "reference_tol": REFERENCE_TOL, "uncertainty_share": UNCERTAINTY_SHARE,
                     "max_fixed": MAX_FIXED, "verdict_variant": "stateless"},
        "rows": rows,
        "command": command,
        "date": date,
        "elapsed_s": time.perf_counter() - t0,
    }


def main(argv: list[str] | None = None) -> None:
    """``python -m roller_gym.bench.cost``: measure this part alone and put it into an
    existing results file (``--out``'s ``benchmarks/workprecision.json``, under ``"cost"``),
    then render the page again from that file. The rest of the file is kept as it was
    measured; the part records its own command and date."""
    import argparse

    from roller_gym.bench import maintainers, report

    p = argparse.ArgumentParser(description=main.__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="a small sample")
    p.add_argument("--out", type=Path, default=Path("docs"),
                   help="the docs folder holding benchmarks/workprecision.json (default ./docs)")
    args = p.parse_args(argv)
    path = report.results_path(args.out)
    if not path.is_file():
        raise SystemExit(f"no results file at {path}: `roller-gym benchmark` measures one")
    results = records.load_results(path)
    command = "python -m roller_gym.bench.cost" + " --quick" * args.quick + (
        f" --out {args.out}" if args.out != Path("docs") else "")
    results["cost"] = measure(CostConfig.make(args.quick), command)
    records.save_results(results, path)
    print(f"wrote {path}\nwrote {report.write(results, args.out)}")
    print(f"wrote {maintainers.write(args.out)}")


if __name__ == "__main__":
    main()
